//! Shared by the integration tests: a GPU context with the Khronos validation layer on whenever
//! it is installed (always under CI), and a check that it reported nothing, teardown included.
#![allow(dead_code)]

pub mod shapes;
pub mod webdriver;

use irad::gpu::{validation_layer_available, Context, ContextOptions, Validation};

/// Whether the tests run under CI (`CI=true`), where every optional tool must be present.
pub fn under_ci() -> bool {
    std::env::var("CI").is_ok_and(|v| !v.is_empty() && v != "false" && v != "0")
}

/// Runs `test` on the default device with validation on when the layer is installed, then
/// drops the context and fails on any validation message (leaks are reported at teardown).
pub fn with_gpu(test: impl FnOnce(&Context)) {
    let validate = validation_layer_available();
    if !validate {
        assert!(!under_ci(), "the Khronos validation layer is not installed (apt-get install vulkan-validationlayers)");
        eprintln!("note: validation layer not installed; running without it");
    }
    // IRAD_DEVICE picks the device as --device does (scripts/gpu-check.sh); IRAD_FORCE_STAGING
    // puts every buffer behind staging copies (scripts/test.sh runs the GPU tests so once more).
    let options = ContextOptions {
        validation: if validate {
            Validation::On
        } else {
            Validation::Off
        },
        ..ContextOptions::from_env().unwrap_or_else(|e| panic!("{e}"))
    };
    let ctx = Context::new(&options).unwrap_or_else(|e| panic!("no GPU context: {e}"));
    let log = ctx.validation_log();
    test(&ctx);
    drop(ctx);
    let messages = log.messages();
    assert!(
        messages.is_empty(),
        "{} validation message(s):\n{}",
        messages.len(),
        messages.join("\n")
    );
}

/// scenes/NAME/scene.toml at WIDTH x HEIGHT pixels.
pub fn scene_file(name: &str, width: u32, height: u32) -> irad::scene::Scene {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("scenes")
        .join(name)
        .join("scene.toml");
    let mut scene = irad::scene::load(&path).unwrap_or_else(|e| panic!("{e}"));
    scene.camera.width = width;
    scene.camera.height = height;
    scene
}

/// The image's mean luminance (Rec. 709 weights).
pub fn luminance_mean(image: &irad::image::Image) -> f64 {
    let m = image.mean();
    0.2126 * m[0] + 0.7152 * m[1] + 0.0722 * m[2]
}

/// Mean and standard error of the mean of per-seed values.
pub fn mean_and_stderr(values: &[f64]) -> (f64, f64) {
    let n = values.len() as f64;
    let mean = values.iter().sum::<f64>() / n;
    let var = values.iter().map(|m| (m - mean).powi(2)).sum::<f64>() / (n - 1.0);
    (mean, (var / n).sqrt())
}

/// A scratch folder under the system's temporary folder, removed when dropped.
pub struct Scratch(pub std::path::PathBuf);

impl Scratch {
    /// irad-PREFIX-PID-NAME, emptied first.
    pub fn new(prefix: &str, name: &str) -> Scratch {
        let dir = std::env::temp_dir().join(format!("irad-{prefix}-{}-{name}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        Scratch(dir)
    }
}

impl Drop for Scratch {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

/// Every scenes/**/scene.toml of the repository, sorted.
pub fn shipped_scenes() -> Vec<std::path::PathBuf> {
    fn walk(dir: &std::path::Path, found: &mut Vec<std::path::PathBuf>) {
        for entry in std::fs::read_dir(dir).unwrap() {
            let path = entry.unwrap().path();
            if path.is_dir() {
                walk(&path, found);
            } else if path.file_name().is_some_and(|n| n == "scene.toml") {
                found.push(path);
            }
        }
    }
    let mut found = Vec::new();
    walk(
        &std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes"),
        &mut found,
    );
    found.sort();
    found
}
