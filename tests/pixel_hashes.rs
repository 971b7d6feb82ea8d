//! The guard of a refactor: every method renders two scenes at 24 x 16 pixels with small
//! counts and fixed seeds, and the image's bits must hash to what tests/data/pixel_hashes.txt
//! recorded (FNV-1a over every f32 of the image, then each extra map). The bits are the
//! device's: the file holds lavapipe's (this project's CI device); elsewhere the test only
//! reports. `IRAD_RECORD_PIXEL_HASHES=1` rewrites the file, for a change that means to alter
//! images (say which in its commit).

mod common;

use irad::methods::renderers::Renderers;
use irad::methods::Method;
use irad::scene::gpu::GpuScene;

use common::{scene_file, with_gpu};

/// (method, scene, settings): each method on its home scene and one more.
const CASES: &[(&str, &str, &str)] = &[
    ("reference", "cornell-box", "spp = 4\nseed = 3"),
    ("reference", "glossy-env", "spp = 4\nseed = 3"),
    ("ir", "cornell-box", "vpls = 64\nframes = 2\nseed = 3"),
    (
        "ir",
        "failure/corner-light",
        "vpls = 64\nframes = 2\nseed = 3",
    ),
    ("bir", "cornell-box", "vpls = 64\nframes = 2\nseed = 3"),
    ("bir", "failure/u-office", "vpls = 64\nframes = 2\nseed = 3"),
    (
        "bundles",
        "failure/glossy-cornell",
        "frames = 2\niterations = 8\nseed = 3",
    ),
    (
        "bundles",
        "spot-light",
        "frames = 2\niterations = 8\nseed = 3",
    ),
    ("env", "glossy-env", "frames = 2\nspp = 8\nseed = 3"),
    ("env", "failure/sun-behind", "frames = 2\nspp = 8\nseed = 3"),
    ("lightfield", "car-headlights", "frames = 2\nseed = 3"),
    (
        "lightfield",
        "failure/headlight-wall",
        "frames = 2\nseed = 3",
    ),
];

fn fnv1a(hash: &mut u64, bytes: &[u8]) {
    for &b in bytes {
        *hash ^= b as u64;
        *hash = hash.wrapping_mul(0x100000001b3);
    }
}

fn data_file() -> std::path::PathBuf {
    std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/pixel_hashes.txt")
}

#[test]
fn every_method_renders_the_recorded_bits() {
    with_gpu(|ctx| {
        let renderers = Renderers::default();
        let mut lines = Vec::new();
        for &(name, scene_name, settings) in CASES {
            let scene = scene_file(scene_name, 24, 16);
            let gpu = GpuScene::upload(ctx, &scene).unwrap();
            let params: toml::Table = settings.parse().unwrap();
            let method = Method::from_params(name, &params).unwrap_or_else(|e| panic!("{e}"));
            let out = renderers
                .run(ctx, &method, &scene, &gpu, |_, _| {})
                .unwrap_or_else(|e| panic!("{name} on {scene_name}: {e}"));
            let mut hash = 0xcbf29ce484222325u64;
            fnv1a(&mut hash, bytemuck::cast_slice(&out.image.pixels));
            for (_, map) in &out.maps {
                fnv1a(&mut hash, bytemuck::cast_slice(&map.pixels));
            }
            lines.push(format!("{name} {scene_name} {hash:016x}"));
        }
        let text = lines.join("\n") + "\n";
        if std::env::var("IRAD_RECORD_PIXEL_HASHES").is_ok_and(|v| v == "1") {
            std::fs::write(data_file(), &text).unwrap();
            return;
        }
        let device = ctx.info().name.clone();
        if !device.contains("llvmpipe") {
            eprintln!("{device}: the recorded bits are lavapipe's; this device renders:\n{text}");
            return;
        }
        let recorded = std::fs::read_to_string(data_file()).unwrap();
        let differ: Vec<String> = lines
            .iter()
            .zip(recorded.lines())
            .filter(|(now, then)| now.as_str() != *then)
            .map(|(now, then)| format!("now {now}, recorded {then}"))
            .collect();
        assert_eq!(
            lines.len(),
            recorded.lines().count(),
            "cases changed: record again"
        );
        assert!(differ.is_empty(), "images changed:\n{}", differ.join("\n"));
    });
}
