//! `irad render`'s outputs as a unit: `-o` naming a folder writes `render.*` in it; every check
//! that can fail (exposure, output folder, a folder in an output's place) fails before the
//! render, leaving the previous files as they were.

use std::fs;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn irad(args: &[&str], cwd: Option<&Path>) -> Output {
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_irad"));
    cmd.args(args).env("IRAD_VALIDATE", "1");
    if let Some(dir) = cwd {
        cmd.current_dir(dir);
    }
    cmd.output().unwrap()
}

fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("irad-outputs-{}-{name}", std::process::id()));
    let _ = fs::remove_dir_all(&dir);
    fs::create_dir_all(&dir).unwrap();
    dir
}

/// A 16x16 point-light plane: a render takes a fraction of a second.
fn tiny_scene(dir: &Path) -> PathBuf {
    let obj = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/point-light-plane");
    for f in ["point-light-plane.obj", "point-light-plane.mtl"] {
        fs::copy(obj.join(f), dir.join(f)).unwrap();
    }
    let text = fs::read_to_string(obj.join("scene.toml"))
        .unwrap()
        .replace("resolution = [128, 128]", "resolution = [16, 16]");
    assert!(text.contains("[16, 16]"));
    let path = dir.join("tiny.toml");
    fs::write(&path, text).unwrap();
    path
}

/// Every file under `dir`, by name, with its bytes.
fn snapshot(dir: &Path) -> Vec<(String, Vec<u8>)> {
    let mut files: Vec<(String, Vec<u8>)> = fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.is_file())
        .map(|p| {
            let name = p.file_name().unwrap().to_string_lossy().into_owned();
            (name, fs::read(&p).unwrap())
        })
        .collect();
    files.sort();
    files
}

/// A failure with one error line naming `needles`, before the render started.
fn assert_fails_before_rendering(o: &Output, needles: &[&str]) {
    let err = String::from_utf8_lossy(&o.stderr);
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(!o.status.success(), "expected failure:\n{out}{err}");
    assert!(!err.contains("panicked"), "{err}");
    assert!(
        !out.contains("rendering"),
        "it rendered before failing:\n{out}"
    );
    for n in needles {
        assert!(err.contains(n), "`{n}` missing from: {err}");
    }
}

/// `-o DIR/`, `-o DIR` (existing) and `-o .` write `render.exr`, `.png` and `.json` in the
/// folder, the JSON naming its images; no hidden `.exr` or `..exr`.
#[test]
fn o_naming_a_folder_writes_render_files_in_it() {
    let dir = temp_dir("folder");
    let scene = tiny_scene(&dir);
    let scene = scene.to_str().unwrap();
    let slash = dir.join("a/");
    let o = irad(
        &["render", scene, "--spp", "1", "-o", slash.to_str().unwrap()],
        None,
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let names = |d: &Path| -> Vec<String> { snapshot(d).into_iter().map(|(n, _)| n).collect() };
    assert_eq!(
        names(&dir.join("a")),
        ["render.exr", "render.json", "render.png"]
    );
    let record = irad::image::RenderRecord::read(&dir.join("a/render.json")).unwrap();
    assert_eq!(record.files, ["render.exr", "render.png"]);
    // An existing folder without the slash, and `.` from inside it.
    let o = irad(
        &[
            "render",
            scene,
            "--spp",
            "1",
            "-o",
            dir.join("a").to_str().unwrap(),
        ],
        None,
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert_eq!(
        names(&dir.join("a")),
        ["render.exr", "render.json", "render.png"]
    );
    fs::create_dir_all(dir.join("b")).unwrap();
    let o = irad(
        &["render", scene, "--spp", "1", "-o", "."],
        Some(&dir.join("b")),
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert_eq!(
        names(&dir.join("b")),
        ["render.exr", "render.json", "render.png"]
    );
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(text.contains("render.png and ./render.json"), "{text}");
    let _ = fs::remove_dir_all(&dir);
}

/// `--exposure NaN` is refused before anything renders, and the previous EXR, PNG and JSON
/// stay byte for byte.
#[test]
fn a_nan_exposure_renders_nothing_and_keeps_the_previous_set() {
    let dir = temp_dir("exposure");
    let scene = tiny_scene(&dir);
    let out = dir.join("out/plane");
    let o = irad(
        &[
            "render",
            scene.to_str().unwrap(),
            "--spp",
            "1",
            "-o",
            out.to_str().unwrap(),
        ],
        None,
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let before = snapshot(&dir.join("out"));
    assert_eq!(before.len(), 3);
    let o = irad(
        &[
            "render",
            scene.to_str().unwrap(),
            "--spp",
            "2",
            "--exposure",
            "NaN",
            "-o",
            out.to_str().unwrap(),
        ],
        None,
    );
    assert_fails_before_rendering(&o, &["exposure", "NaN"]);
    assert_eq!(snapshot(&dir.join("out")), before);
    let _ = fs::remove_dir_all(&dir);
}

/// An output folder that cannot be created (a file is in the way), or a folder where the PNG
/// goes, fails before rendering and leaves the previous files.
#[test]
fn an_unwritable_output_fails_before_rendering() {
    let dir = temp_dir("unwritable");
    let scene = tiny_scene(&dir);
    let scene = scene.to_str().unwrap();
    fs::write(dir.join("file"), "not a folder").unwrap();
    let o = irad(
        &[
            "render",
            scene,
            "--spp",
            "1",
            "-o",
            dir.join("file/sub/x").to_str().unwrap(),
        ],
        None,
    );
    assert_fails_before_rendering(&o, &["output folder", "file/sub"]);

    let out = dir.join("set/x");
    fs::create_dir_all(dir.join("set/x.png")).unwrap();
    fs::write(dir.join("set/x.exr"), "the previous EXR").unwrap();
    fs::write(dir.join("set/x.json"), "the previous JSON").unwrap();
    let before = snapshot(&dir.join("set"));
    let o = irad(
        &["render", scene, "--spp", "1", "-o", out.to_str().unwrap()],
        None,
    );
    assert_fails_before_rendering(&o, &["x.png", "is a folder"]);
    assert_eq!(snapshot(&dir.join("set")), before);
    let _ = fs::remove_dir_all(&dir);
}
