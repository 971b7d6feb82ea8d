//! The `irad` binary: `info` names the device and its limits, the self-check passes, and every
//! missing piece (loader, device, validation layer, bad --device) is one line of error, no panic.

use std::process::{Command, Output};

fn irad(args: &[&str], env: &[(&str, &str)]) -> Output {
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_irad"));
    cmd.args(args)
        .env_remove("IRAD_VALIDATE")
        .env_remove("IRAD_VULKAN_LIBRARY")
        .env_remove("IRAD_FORCE_STAGING");
    for (k, v) in env {
        cmd.env(k, v);
    }
    cmd.output().unwrap()
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// A failure with one `error:` line and no panic.
fn assert_clean_error(o: &Output, needles: &[&str]) {
    let err = stderr(o);
    assert!(!o.status.success(), "expected failure, got success: {err}");
    assert!(!err.contains("panicked"), "{err}");
    let lines: Vec<&str> = err.lines().filter(|l| !l.trim().is_empty()).collect();
    assert_eq!(lines.len(), 1, "expected one line: {err}");
    assert!(lines[0].starts_with("error: "), "{err}");
    for n in needles {
        assert!(err.contains(n), "`{n}` missing from: {err}");
    }
}

#[test]
fn info_lists_lavapipe_and_its_limits() {
    let o = irad(&["info"], &[]);
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(
        out.contains("llvmpipe") || out.contains("lavapipe") || !out.contains("CPU"),
        "{out}"
    );
    for label in [
        "max storage buffer range",
        "shared memory",
        "workgroup",
        "subgroup size",
        "f32 atomic add",
        "timestamps",
    ] {
        assert!(out.contains(label), "`{label}` missing:\n{out}");
    }
    assert!(
        out.contains("* 0:") || out.contains("* 1:") || out.contains("* 2:"),
        "no device marked:\n{out}"
    );
}

#[test]
fn selfcheck_passes_with_validation() {
    let o = irad(&["selfcheck"], &[("IRAD_VALIDATE", "1")]);
    assert!(
        o.status.success(),
        "{}{}",
        String::from_utf8_lossy(&o.stdout),
        stderr(&o)
    );
    assert!(String::from_utf8_lossy(&o.stdout).contains("selfcheck passed"));
}

#[test]
fn a_bad_device_is_one_line_naming_it_and_the_devices() {
    assert_clean_error(
        &irad(&["--device", "99", "selfcheck"], &[]),
        &["--device 99", "0: "],
    );
    assert_clean_error(
        &irad(&["--device", "no-such-gpu", "selfcheck"], &[]),
        &["no-such-gpu", "irad info"],
    );
    // The same index from IRAD_DEVICE is named as the variable the user set.
    let o = irad(&["selfcheck"], &[("IRAD_DEVICE", "99")]);
    assert_clean_error(&o, &["IRAD_DEVICE=99:", "0: "]);
    assert!(!stderr(&o).contains("--device"), "{}", stderr(&o));
}

/// Environment switches are read by their value: `IRAD_FORCE_STAGING=false` leaves staging
/// off (it forced it by being present), and a value that is neither on nor off is an error
/// naming the variable.
#[test]
fn environment_switches_are_read_by_value() {
    let staging = |value: &str| {
        let o = irad(&["info"], &[("IRAD_FORCE_STAGING", value)]);
        (
            o.status.success(),
            String::from_utf8_lossy(&o.stdout).contains("staging: forced"),
        )
    };
    for off in ["false", "0", "no", ""] {
        assert_eq!(staging(off), (true, false), "IRAD_FORCE_STAGING={off:?}");
    }
    for on in ["1", "true", "yes"] {
        assert_eq!(staging(on), (true, true), "IRAD_FORCE_STAGING={on:?}");
    }
    for (name, args) in [
        ("IRAD_FORCE_STAGING", &["info"][..]),
        ("IRAD_VALIDATE", &["methods"][..]),
    ] {
        assert_clean_error(
            &irad(args, &[(name, "junk")]),
            &[&format!("{name}=junk:"), "true", "false"],
        );
    }
    // IRAD_VALIDATE=false leaves validation off: with no layer to be found (VK_LAYER_PATH),
    // validation on is an error, so a selfcheck that passes shows it off.
    let o = irad(
        &["selfcheck"],
        &[
            ("IRAD_VALIDATE", "false"),
            ("VK_LAYER_PATH", "/nonexistent"),
        ],
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let o = irad(
        &["selfcheck"],
        &[("IRAD_VALIDATE", "1"), ("VK_LAYER_PATH", "/nonexistent")],
    );
    assert_clean_error(&o, &["validation layer"]);
}

#[test]
fn a_missing_loader_says_what_to_install() {
    let o = irad(
        &["info"],
        &[("IRAD_VULKAN_LIBRARY", "/nonexistent/libvulkan.so.1")],
    );
    assert_clean_error(&o, &["Vulkan loader", "libvulkan1"]);
}

#[test]
fn no_device_says_what_to_install() {
    let o = irad(
        &["selfcheck"],
        &[
            ("VK_ICD_FILENAMES", "/nonexistent/icd.json"),
            ("VK_DRIVER_FILES", "/nonexistent/icd.json"),
        ],
    );
    assert_clean_error(&o, &["no Vulkan device", "mesa-vulkan-drivers"]);
}

#[test]
fn a_missing_validation_layer_says_what_to_install() {
    let o = irad(
        &["selfcheck"],
        &[
            ("IRAD_VALIDATE", "1"),
            ("VK_LAYER_PATH", "/nonexistent"),
            ("XDG_DATA_HOME", "/nonexistent"),
            ("XDG_DATA_DIRS", "/nonexistent"),
        ],
    );
    assert_clean_error(&o, &["validation layer", "vulkan-validationlayers"]);
}

/// Output piped into a reader that has gone (`irad methods | head`) ends irad quietly, as
/// other tools end, not with a panic in `println!`.
#[test]
fn a_closed_output_pipe_ends_irad_quietly() {
    use std::io::Read;
    use std::process::Stdio;
    let mut child = Command::new(env!("CARGO_BIN_EXE_irad"))
        .arg("methods")
        .arg("bir")
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    // No reader is left before irad writes its first line.
    drop(child.stdout.take());
    let mut err = String::new();
    child
        .stderr
        .take()
        .unwrap()
        .read_to_string(&mut err)
        .unwrap();
    child.wait().unwrap();
    assert!(!err.contains("panicked"), "{err}");
    assert_eq!(err, "");
}

#[test]
fn help_explains_the_commands() {
    let o = irad(&["--help"], &[]);
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success());
    for c in [
        "info",
        "selfcheck",
        "shaders",
        "bench",
        "--device",
        "IRAD_VALIDATE",
    ] {
        assert!(out.contains(c), "`{c}` missing from --help:\n{out}");
    }
}

fn temp_dir(name: &str) -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("irad-cli-{name}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

#[test]
fn render_writes_exr_png_and_json() {
    let dir = temp_dir("render");
    let out = dir.join("spot");
    let scene = concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/spot-light/scene.toml");
    let o = irad(
        &[
            "render",
            scene,
            "--spp",
            "2",
            "--resolution",
            "40x30",
            "-o",
            out.to_str().unwrap(),
        ],
        &[("IRAD_VALIDATE", "1")],
    );
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{}{text}", stderr(&o));
    assert!(!stderr(&o).contains("validation"), "{}", stderr(&o));
    for label in ["gbuffer", "reference paths", "samples/s", "wrote"] {
        assert!(text.contains(label), "`{label}` missing:\n{text}");
    }
    let image = irad::image::exr::read(&out.with_extension("exr")).unwrap();
    assert_eq!((image.width, image.height), (40, 30), "--resolution");
    assert!(image.pixels.iter().flatten().all(|v| v.is_finite()));
    assert!(image.mean()[0] > 0.0, "the spot light scene rendered black");
    assert!(out.with_extension("png").exists());
    let record = irad::image::RenderRecord::read(&out.with_extension("json")).unwrap();
    assert_eq!(record.method, "reference");
    assert_eq!(record.samples, 2);
    assert_eq!(record.scene_hash.len(), 16);

    // Against itself as the reference: every metric is zero.
    let o = irad(
        &[
            "render",
            scene,
            "--spp",
            "2",
            "--resolution",
            "40x30",
            "-o",
            dir.join("again").to_str().unwrap(),
            "--reference",
            out.with_extension("exr").to_str().unwrap(),
        ],
        &[],
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let record = irad::image::RenderRecord::read(&dir.join("again.json")).unwrap();
    let m = record.metrics.expect("metrics with --reference");
    assert_eq!((m.rel_mse, m.bias, m.nan_inf), (0.0, 0.0, 0));
    std::fs::remove_dir_all(&dir).ok();
}

/// `irad compare`: two EXRs give the figures `render --reference` gives, the figures as JSON
/// and three error maps with colour bars; two folders of frames give each frame's and the
/// sequence's; a file against a folder and a missing frame are refused by name.
#[test]
fn compare_scores_images_and_folders() {
    let dir = temp_dir("compare");
    let scene = concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/spot-light/scene.toml");
    let path = |name: &str| dir.join(name).to_str().unwrap().to_string();
    for (name, spp) in [("ref", "16"), ("x", "2")] {
        let o = irad(
            &[
                "render",
                scene,
                "--spp",
                spp,
                "--resolution",
                "24x16",
                "-o",
                &path(name),
            ],
            &[],
        );
        assert!(o.status.success(), "{}", stderr(&o));
    }
    let o = irad(
        &[
            "render",
            scene,
            "--spp",
            "2",
            "--resolution",
            "24x16",
            "-o",
            &path("scored"),
            "--reference",
            &path("ref.exr"),
        ],
        &[],
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let record = irad::image::RenderRecord::read(&dir.join("scored.json")).unwrap();
    assert!(record.reference.as_deref().unwrap().ends_with("ref.exr"));
    assert!(std::path::Path::new(record.scene_path.as_deref().unwrap()).is_absolute());
    assert!(!record.git_commit.is_empty());
    // The scene's way to the device: parsing, the builds and the whole upload, in ms.
    let load = record.load.expect("load times");
    assert!(
        load.parse_ms > 0.0 && load.triangle_bvh_ms > 0.0,
        "{load:?}"
    );
    assert!(
        load.upload_ms >= load.triangle_bvh_ms + load.light_bvh_ms,
        "{load:?}"
    );
    let o = irad(
        &[
            "compare",
            &path("x.exr"),
            &path("ref.exr"),
            "-o",
            &path("cmp"),
        ],
        &[],
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(text.contains("relMSE") && text.contains("FLIP"), "{text}");
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("cmp.json")).unwrap()).unwrap();
    let expected = record.metrics.unwrap();
    assert_eq!(json["metrics"]["rel_mse"].as_f64(), Some(expected.rel_mse));
    assert_eq!(json["metrics"]["bias"].as_f64(), Some(expected.bias));
    assert!(json["metrics"]["flip"].as_f64().is_some_and(|f| f > 0.0));
    for map in ["cmp.png", "cmp_signed.png", "cmp_flip.png"] {
        let decoder = png::Decoder::new(std::io::BufReader::new(
            std::fs::File::open(dir.join(map)).unwrap(),
        ));
        let info = decoder.read_info().unwrap();
        let (w, h) = (info.info().width, info.info().height);
        // The map (24x16) above its bar, widened for the labels.
        assert!(w >= 24 && h > 16 + 8, "{map}: {w}x{h}");
    }
    // Folders: frame 3 of each twice, the test's frames once the reference's.
    for (folder, from) in [("a", "x.exr"), ("b", "ref.exr")] {
        std::fs::create_dir_all(dir.join(folder)).unwrap();
        for f in ["frame_0003.exr", "frame_0004.exr"] {
            std::fs::copy(dir.join(from), dir.join(folder).join(f)).unwrap();
        }
    }
    let o = irad(
        &["compare", &path("a"), &path("b"), "-o", &path("seq")],
        &[],
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("seq/compare.json")).unwrap())
            .unwrap();
    assert_eq!(json["frames"].as_array().unwrap().len(), 2);
    assert_eq!(json["frames"][1]["frame"], 4);
    assert_eq!(
        json["sequence"]["mean"]["rel_mse"].as_f64(),
        Some(expected.rel_mse)
    );
    assert!(dir.join("seq/frame_0004_signed.png").is_file());
    // A reference with more frames than the test: the test's are scored, the rest said.
    std::fs::copy(dir.join("ref.exr"), dir.join("b/frame_0005.exr")).unwrap();
    let o = irad(&["compare", &path("a"), &path("b")], &[]);
    assert!(o.status.success(), "{}", stderr(&o));
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(
        text.contains("1 of the reference's frames are not in"),
        "{text}"
    );
    std::fs::remove_file(dir.join("b/frame_0005.exr")).unwrap();
    // Refusals, each one line naming what is wrong.
    let o = irad(&["compare", &path("x.exr"), &path("b")], &[]);
    assert_clean_error(&o, &["a folder", "two EXRs or two folders"]);
    std::fs::remove_file(dir.join("b/frame_0004.exr")).unwrap();
    let o = irad(&["compare", &path("a"), &path("b")], &[]);
    assert_clean_error(&o, &["lacks 1", "frame_0004.exr"]);
    let o = irad(&["compare", &path("missing.exr"), &path("ref.exr")], &[]);
    assert_clean_error(&o, &["missing.exr"]);
    std::fs::remove_dir_all(&dir).ok();
}

/// A sequence's frames have one size: resuming it at another `--resolution` is refused, naming
/// both sizes, and the frames already there stay as they are.
#[test]
fn a_sequence_resumed_at_another_resolution_is_refused() {
    let dir = temp_dir("sequence-resolution");
    let scene = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/scenes/cornell-circling/scene.toml"
    );
    let out = dir.join("seq");
    let render = |size: &str| {
        irad(
            &[
                "render",
                scene,
                "--sequence=0..2",
                "--samples-per-frame",
                "1",
                "--resolution",
                size,
                "-o",
                out.to_str().unwrap(),
            ],
            &[],
        )
    };
    let o = render("24x16");
    assert!(o.status.success(), "{}", stderr(&o));
    let o = render("20x16");
    assert_clean_error(&o, &["another sequence", "24x16", "20x16"]);
    let frame = irad::image::exr::read(&out.join("frame_0001.exr")).unwrap();
    assert_eq!((frame.width, frame.height), (24, 16));
    std::fs::remove_dir_all(&dir).ok();
}

/// `--html` writes the viewer's page: OUT/sequence.html with every frame, the reference's
/// frames, per-frame relMSE and FLIP maps; OUT.html beside a still's EXR.
#[test]
fn renders_write_their_viewer_pages() {
    let dir = temp_dir("html");
    let scene = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/scenes/cornell-circling/scene.toml"
    );
    let sequence = |out: &str, samples: &str, extra: &[&str]| {
        let out = dir.join(out);
        let mut args = vec![
            "render",
            scene,
            "--sequence=0..2",
            "--samples-per-frame",
            samples,
            "--resolution",
            "24x16",
            "-o",
            out.to_str().unwrap(),
        ];
        args.extend_from_slice(extra);
        let o = irad(&args, &[]);
        assert!(o.status.success(), "{}", stderr(&o));
    };
    // The reference with more samples, so that each frame has an error of its own.
    sequence("ref", "8", &[]);
    let reference = dir.join("ref");
    sequence(
        "seq",
        "2",
        &["--html", "--reference", reference.to_str().unwrap()],
    );
    let html = std::fs::read_to_string(dir.join("seq/sequence.html")).unwrap();
    let data = viewer_data(&html);
    assert_eq!(data["names"], serde_json::json!(["render", "reference"]));
    assert_eq!(data["reference"], "reference");
    // Each frame's relMSE is the one sequence.json scored it with (the frames paired right).
    let record: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("seq/sequence.json")).unwrap())
            .unwrap();
    let frames = data["frames"].as_array().unwrap();
    assert_eq!(frames.len(), 2);
    for (k, frame) in frames.iter().enumerate() {
        assert_eq!(frame["number"], k);
        let scored = record["rendered"][k]["metrics"]["rel_mse"]
            .as_f64()
            .unwrap();
        let shown = frame["relmse"].as_f64().unwrap();
        assert!(
            scored > 0.0 && (shown - scored).abs() <= 1e-9 * scored,
            "frame {k}: {shown} against {scored}"
        );
        assert!(frame["images"][0]["flip"].is_string() && frame["images"][1].get("flip").is_none());
    }
    // A still: frame 1 as a still against the reference's frame 1.
    let still = dir.join("still");
    let o = irad(
        &[
            "render",
            scene,
            "--frame",
            "1",
            "--spp",
            "2",
            "--resolution",
            "24x16",
            "-o",
            still.to_str().unwrap(),
            "--reference",
            reference.join("frame_0001.exr").to_str().unwrap(),
            "--html",
        ],
        &[],
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let data = viewer_data(&std::fs::read_to_string(dir.join("still.html")).unwrap());
    assert_eq!(data["names"], serde_json::json!(["render", "reference"]));
    assert!(data["frames"][0]["images"][0]["flip"].is_string());
    std::fs::remove_dir_all(&dir).ok();
}

/// The viewer's data in a page irad wrote.
fn viewer_data(html: &str) -> serde_json::Value {
    let start = html.find("const IRAD_DATA = ").expect("the viewer's data") + 18;
    let end = start + html[start..].find(";\n").expect("its end");
    serde_json::from_str(&html[start..end]).expect("JSON")
}

#[test]
fn render_errors_name_the_file() {
    let o = irad(&["render", "no/such/scene.toml"], &[]);
    assert_clean_error(&o, &["no/such/scene.toml"]);

    let dir = temp_dir("bad-reference");
    let scene = concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/spot-light/scene.toml");
    let missing = dir.join("missing.exr");
    let o = irad(
        &[
            "render",
            scene,
            "--spp",
            "1",
            "-o",
            dir.join("x").to_str().unwrap(),
            "--reference",
            missing.to_str().unwrap(),
        ],
        &[],
    );
    assert_clean_error(&o, &["missing.exr"]);
    // clap's own message: its first line names the flag, the value and the form.
    let o = irad(&["render", scene, "--resolution", "640x0"], &[]);
    let err = stderr(&o);
    assert!(!o.status.success() && !err.contains("panicked"), "{err}");
    let first = err.lines().next().unwrap_or_default();
    for needle in ["error: ", "--resolution", "640x0", "WIDTHxHEIGHT", "16384"] {
        assert!(first.contains(needle), "`{needle}` missing from: {err}");
    }
    std::fs::remove_dir_all(&dir).ok();
}

/// `irad luminaire generate` writes a luminaire that loads back with the asked geometry, and
/// refuses a bad value in one line.
#[test]
fn luminaire_generate_writes_a_loadable_luminaire() {
    let dir = std::env::temp_dir().join(format!("irad-cli-luminaire-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let out = dir.to_str().unwrap();
    let o = irad(
        &[
            "luminaire",
            "generate",
            "--emitter",
            "disk",
            "--grid",
            "5x3",
            "--resolution",
            "16x8",
            "--basis",
            "bilinear",
            "-o",
            out,
        ],
        &[],
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let lum = irad::scene::luminaire::Luminaire::load(&dir.join("luminaire.toml")).unwrap();
    assert_eq!(lum.geometry.grid, [5, 3]);
    assert_eq!(lum.geometry.resolution, [16, 8]);
    assert_eq!(lum.geometry.basis, irad::scene::luminaire::Basis::Bilinear);
    assert!(lum.images.iter().flatten().any(|t| t.x > 0.0));
    let o = irad(&["luminaire", "generate", "--delta", "0", "-o", out], &[]);
    assert_clean_error(&o, &["--delta 0", "> 0"]);
    // A sequence: three atlases, the beam lowered 6 degrees over them.
    let seq = dir.join("seq");
    let o = irad(
        &[
            "luminaire",
            "generate",
            "--emitter",
            "reflector",
            "--grid",
            "3x3",
            "--resolution",
            "8x8",
            "--frames",
            "3",
            "--sweep",
            "6",
            "-o",
            seq.to_str().unwrap(),
        ],
        &[],
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let lum = irad::scene::luminaire::Luminaire::load(&seq.join("luminaire.toml")).unwrap();
    assert_eq!(lum.sequence.len(), 3);
    assert_ne!(lum.sequence[0], lum.sequence[2]);
    let o = irad(
        &[
            "luminaire",
            "generate",
            "--emitter",
            "disk",
            "--frames",
            "2",
            "-o",
            out,
        ],
        &[],
    );
    assert_clean_error(&o, &["--frames 2", "headlight or reflector"]);
    let _ = std::fs::remove_dir_all(&dir);
}

/// `irad bench lightfield` prints Fig. 4.12's breakdown, and names a bad strategy.
#[test]
fn bench_lightfield_prints_the_breakdown() {
    let scene = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/scenes/failure/headlight-wall/scene.toml"
    );
    let o = irad(
        &[
            "bench",
            "lightfield",
            scene,
            "--resolution",
            "16x12",
            "--spp",
            "8",
            "--frames",
            "1",
            "--repeats",
            "1",
            "--strategies",
            "restricted",
        ],
        &[],
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let text = String::from_utf8_lossy(&o.stdout);
    for needle in ["A est.", "sampling", "shadows", "restricted", "per build"] {
        assert!(text.contains(needle), "`{needle}` not in:\n{text}");
    }
    let o = irad(&["bench", "lightfield", scene, "--strategies", "nope"], &[]);
    assert_clean_error(&o, &["--strategies", "nope", "restricted"]);
}

/// A missing file's OS error said once; an unwritable luminaire folder named;
/// a negative seed one clear message (not clap's tip to write `-- -1`).
#[test]
fn file_and_seed_errors_say_it_once_and_name_the_path() {
    let o = irad(&["render", "no/such/scene.toml"], &[]);
    assert_clean_error(&o, &["no/such/scene.toml", "cannot read it"]);
    assert_eq!(
        stderr(&o).matches("os error 2").count(),
        1,
        "{}",
        stderr(&o)
    );

    let o = irad(
        &[
            "luminaire",
            "generate",
            "--emitter",
            "disk",
            "-o",
            "/proc/irad-lumx",
        ],
        &[],
    );
    assert_clean_error(&o, &["/proc/irad-lumx", "cannot create the folder"]);

    // An 824 GB atlas is refused at once, with its size, before any work.
    let o = irad(
        &[
            "luminaire",
            "generate",
            "--emitter",
            "disk",
            "--grid",
            "64x64",
            "--resolution",
            "4096x4096",
            "-o",
            "/tmp/irad-never-written",
        ],
        &[],
    );
    assert_clean_error(&o, &["68719476736 texels an atlas", "GiB", "4 GiB"]);
    assert!(!std::path::Path::new("/tmp/irad-never-written/images.exr").exists());
    // The flag's own limit is the library's: 16384 passed the flag, then failed with another.
    let o = irad(
        &[
            "luminaire",
            "generate",
            "--resolution",
            "16384x16384",
            "-o",
            "/tmp/irad-never-written",
        ],
        &[],
    );
    let err = stderr(&o);
    assert!(
        !o.status.success() && err.contains("'--resolution") && err.contains("1..=4096"),
        "{err}"
    );

    for seed in ["-1", "4294967296", "x"] {
        let o = irad(&["render", "--seed", seed, "--spp", "1"], &[]);
        let err = stderr(&o);
        assert!(!o.status.success(), "--seed {seed}: {err}");
        assert!(!err.contains("panicked") && !err.contains("-- -1"), "{err}");
        assert!(
            err.contains("0..=4294967295") && err.contains(seed),
            "{err}"
        );
    }
}

/// IRAD_FORCE_STAGING=1 (docs/DESIGN.md "Staging"): `irad info` and the render JSON say staging
/// is forced, and the image is the one rendered without it.
#[test]
fn forced_staging_is_reported_and_changes_no_pixel() {
    let o = irad(&["info"], &[("IRAD_FORCE_STAGING", "1")]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(String::from_utf8_lossy(&o.stdout).contains("staging: forced"));

    let dir = temp_dir("staging");
    let scene = concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/spot-light/scene.toml");
    let render = |name: &str, env: &[(&str, &str)]| {
        let out = dir.join(name);
        let o = irad(
            &["render", scene, "--spp", "2", "-o", out.to_str().unwrap()],
            env,
        );
        assert!(o.status.success(), "{}", stderr(&o));
        (
            irad::image::exr::read(&out.with_extension("exr")).unwrap(),
            irad::image::RenderRecord::read(&out.with_extension("json")).unwrap(),
        )
    };
    let (staged, record) = render(
        "staged",
        &[("IRAD_FORCE_STAGING", "1"), ("IRAD_VALIDATE", "1")],
    );
    assert_eq!(record.staging.as_deref(), Some("forced"));
    let (mapped, record) = render("mapped", &[]);
    assert_eq!(record.staging, None);
    assert_eq!(staged.pixels, mapped.pixels);
    std::fs::remove_dir_all(&dir).ok();
}

/// Sizes that cannot run on the device are refused before any rendering in the user's words:
/// the setting, scene field or file at fault and the largest value that fits, never an
/// internal buffer's name (they were refused as `CubeWeights`, `GBuffer`, `BundleHits`, `Vpls`).
#[test]
fn sizes_over_the_device_limits_are_refused_before_rendering() {
    let scenes = concat!(env!("CARGO_MANIFEST_DIR"), "/scenes");
    let glossy = format!("{scenes}/failure/glossy-cornell/scene.toml");
    let env = format!("{scenes}/glossy-env/scene.toml");
    let range = irad::gpu::list_devices()
        .ok()
        .and_then(|d| {
            let i = irad::gpu::device_info::choose(&d, None).ok()?;
            d.into_iter().find(|x| x.index == i)
        })
        .map_or(u64::MAX, |d| d.max_storage_buffer_range);
    let dir = temp_dir("device-limits");
    // 16384^2 pixels at 64 bytes (the G-buffer) is 16 GiB, over any device's range.
    let big = dir.join("big.toml");
    std::fs::write(
        &big,
        format!(
            "[camera]\nposition = [0, 1, 3.4]\nlook_at = [0, 1, 0]\nfov_y = 40\n\
             resolution = [16384, 16384]\n[[mesh]]\nobj = \"{scenes}/cornell-box/cornell-box.obj\"\n"
        ),
    )
    .unwrap();
    let big = big.to_str().unwrap().to_string();
    let out = dir.join("never").to_str().unwrap().to_string();
    // The largest face resolution: 6 R^2 f32s within the range.
    let faces = irad::methods::device_fit::largest_fitting(4096, range, |r| 24 * r * r);
    let faces_text = faces.to_string();
    let bundles: Vec<&str> = vec![
        "render",
        &glossy,
        "--method",
        "bundles",
        "--iterations",
        "65536",
    ];
    let cube: Vec<&str> = vec![
        "render",
        &env,
        "--method",
        "env",
        "--face-resolution",
        "4096",
    ];
    let pixels: Vec<&str> = vec!["render", &big];
    // 34000 emissive triangles: bir's camera-driven light table measures each at 1024 camera
    // points, 139264000 bytes in one buffer.
    let lights = dir.join("lights.toml");
    let mut obj = String::from("mtllib lights.mtl\nusemtl floor\nv -9 0 -9\nv 9 0 -9\nv 9 0 9\nv -9 0 9\nf 1 4 3 2\nusemtl light\n");
    for k in 0..17000 {
        let (x, z) = ((k % 130) as f32 * 0.1 - 6.5, (k / 130) as f32 * 0.1 - 6.5);
        obj += &format!(
            "v {x} 2 {z}\nv {} 2 {z}\nv {} 2 {}\nv {x} 2 {}\nf -4 -3 -2 -1\n",
            x + 0.05,
            x + 0.05,
            z + 0.05,
            z + 0.05
        );
    }
    std::fs::write(dir.join("lights.obj"), obj).unwrap();
    std::fs::write(
        dir.join("lights.mtl"),
        "newmtl floor\nKd 0.5 0.5 0.5\nnewmtl light\nKd 0 0 0\nKe 1 1 1\n",
    )
    .unwrap();
    std::fs::write(
        &lights,
        "[camera]\nposition = [0, 1, 5]\nlook_at = [0, 0, 0]\nfov_y = 40\nresolution = [8, 8]\n\
         [[mesh]]\nobj = \"lights.obj\"\n",
    )
    .unwrap();
    let lights = lights.to_str().unwrap().to_string();
    let bir: Vec<&str> = vec!["render", &lights, "--method", "bir", "--frames", "1"];
    let ir: Vec<&str> = vec!["render", "--method", "ir", "--vpls", "1048576"];
    // BundleHits at 65536 iterations on 256x256 pixels is 11 GB, over any device's range;
    // ir's 1048576 VPLs need 156716096 bytes, over lavapipe's 128 MiB but within a discrete
    // GPU's; the cube at 4096 needs 402653184 bytes, the same.
    let mut cases: Vec<(Vec<&str>, Vec<&str>)> = vec![
        (
            bundles,
            vec![
                "iterations = 65536 (--iterations)",
                "the largest that fits is",
            ],
        ),
        (
            pixels,
            vec!["big.toml: the image size 16384x16384", "at most", "pixels"],
        ),
    ];
    if range < 402_653_184 {
        cases.push((
            cube,
            vec![
                "face_resolution = 4096 (--face-resolution)",
                "the largest that fits is",
            ],
        ));
    }
    if range < 156_716_096 {
        cases.push((
            ir,
            vec!["vpls = 1048576 (--vpls)", "the largest that fits is"],
        ));
    }
    if range < 139_264_000 {
        cases.push((
            bir,
            vec![
                "light_cdf = true (--light-cdf)",
                "34000 lights",
                "--light-cdf=false",
            ],
        ));
    }
    for (mut args, needles) in cases {
        args.extend(["-o", &out]);
        let start = std::time::Instant::now();
        let o = irad(&args, &[]);
        let mut needles = needles;
        needles.push("maxStorageBufferRange");
        assert_clean_error(&o, &needles);
        for internal in [
            "CubeWeights",
            "GBuffer",
            "BundleHits",
            "Vpls`",
            "buffer `",
            "Contributions",
        ] {
            assert!(!stderr(&o).contains(internal), "{}", stderr(&o));
        }
        assert!(
            start.elapsed().as_secs() < 20,
            "{args:?} took {:?}",
            start.elapsed()
        );
        assert!(!dir.join("never.exr").exists());
    }
    // The largest face resolution the message gives renders.
    if range < 402_653_184 {
        let o = irad(
            &[
                "render",
                &env,
                "--method",
                "env",
                "--face-resolution",
                &faces_text,
                "--spp",
                "2",
                "--frames",
                "1",
                "-o",
                &out,
            ],
            &[],
        );
        assert!(o.status.success(), "{}", stderr(&o));
    }
    std::fs::remove_dir_all(&dir).ok();
}

/// What `irad render ARGS` draws on a terminal in its first 8 s: run under `script`
/// (util-linux), since the bar draws only on a terminal. None where `script` or `timeout` is
/// missing (outside CI only).
fn screen_of_render(name: &str, args: &str) -> Option<String> {
    let have = |tool: &str| {
        Command::new(tool)
            .arg("--version")
            .output()
            .is_ok_and(|o| o.status.success())
    };
    if !have("script") || !have("timeout") {
        assert!(
            !common_under_ci(),
            "`script` and `timeout` (util-linux, coreutils) are needed"
        );
        eprintln!("note: no `script` or `timeout`; skipping");
        return None;
    }
    let dir = temp_dir(name);
    let render = format!(
        "timeout 8 '{}' render {args} -o '{}'",
        env!("CARGO_BIN_EXE_irad"),
        dir.join("never").display()
    );
    let o = Command::new("script")
        .args(["-q", "-c", &render, "/dev/null"])
        .env_remove("IRAD_VALIDATE")
        .output()
        .unwrap();
    std::fs::remove_dir_all(&dir).ok();
    Some(String::from_utf8_lossy(&o.stdout).into_owned())
}

/// A long render shows a progress bar with its time left (without one, `--spp 2000000000`
/// would print nothing for minutes). The bar draws only on a terminal, so the render runs under
/// `script` (util-linux), stopped after a few seconds.
#[test]
fn a_long_render_shows_its_time_left() {
    let Some(screen) = screen_of_render("progress", "--spp 2000000000") else {
        return;
    };
    assert!(
        screen.contains("/2000000000 (") && screen.contains("elapsed,") && screen.contains("left)"),
        "{screen}"
    );
}

/// A single long frame shows how far it has come: bir's frame of 2^20 VPLs runs for minutes
/// on lavapipe, and a bar that counts frames would stand at 0/1 all along. The frame runs in
/// parts (each waited for) and the bar's message counts its dispatches, which must move
/// within a few seconds.
#[test]
fn a_long_frame_shows_its_progress() {
    let Some(screen) = screen_of_render("frame-progress", "--method bir --vpls 1048576 --frames 1")
    else {
        return;
    };
    // "frame 1: N of ~M dispatches" with at least two values of N.
    let counts: std::collections::BTreeSet<&str> = screen
        .split("frame 1: ")
        .skip(1)
        .filter_map(|rest| rest.split(" of ~").next())
        .filter(|n| n.chars().all(|c| c.is_ascii_digit()))
        .collect();
    assert!(
        screen.contains("0/1 (") && counts.len() >= 2,
        "{counts:?}\n{screen}"
    );
}

/// As tests/common's under_ci (this file does not use the GPU helpers).
fn common_under_ci() -> bool {
    std::env::var("CI").is_ok_and(|v| !v.is_empty() && v != "false" && v != "0")
}

/// `irad render --help` groups the method flags by method, a flag the chosen method
/// does not take is one line naming the flag and the method, `irad methods NAME` lists a
/// method's settings with their defaults, and `irad export mitsuba` writes a scene or refuses
/// luminaires by name.
#[test]
fn method_flags_methods_and_export() {
    let o = irad(&["render", "--help"], &[]);
    let help = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success());
    for heading in [
        "Settings of several methods:",
        "Settings of --method reference:",
        "Settings of --method bir:",
        "Settings of --method lightfield:",
    ] {
        assert!(help.contains(heading), "`{heading}` missing:\n{help}");
    }
    let o = irad(
        &[
            "render",
            "--method",
            "reference",
            "--vpls",
            "64",
            "--clamp",
            "5",
        ],
        &[],
    );
    assert_clean_error(&o, &["--vpls does not apply to --method reference"]);
    let o = irad(&["render", "--method", "env", "--spp", "100000"], &[]);
    assert_clean_error(&o, &["--spp 100000: must be in 1..=65536"]);
    let o = irad(&["render", "--method", "bir", "--vpls", "1"], &[]);
    assert_clean_error(&o, &["--vpls 1: must be in 2..=1048576"]);

    let o = irad(&["methods", "env"], &[]);
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(
        out.contains("--spp N  (suite: spp)  default 60, 1..=65536"),
        "{out}"
    );
    assert!(out.contains("--strategy dynamic|uniform-faces"), "{out}");
    assert_clean_error(
        &irad(&["methods", "bidir"], &[]),
        &["unknown method `bidir`"],
    );

    let dir = temp_dir("export");
    let scene = concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/spot-light/scene.toml");
    let o = irad(
        &["export", "mitsuba", scene, "-o", dir.to_str().unwrap()],
        &[],
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(
        out.contains("approximation: ") && out.contains("spot"),
        "{out}"
    );
    let xml = std::fs::read_to_string(dir.join("scene.xml")).unwrap();
    assert!(xml.contains("<scene version=\"3.0.0\">"), "{xml}");
    let headlights = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/scenes/car-headlights/scene.toml"
    );
    let o = irad(
        &[
            "export",
            "mitsuba",
            headlights,
            "-o",
            dir.join("no").to_str().unwrap(),
        ],
        &[],
    );
    assert_clean_error(&o, &["Mitsuba has no light-field luminaires"]);
    std::fs::remove_dir_all(&dir).ok();
}

/// A switch given its value after a space takes the value as the scene: the error names the
/// switch and how to write it, whatever the value (`off`, not only true or false).
#[test]
fn a_switch_followed_by_its_value_gets_a_tip_naming_the_switch() {
    let o = irad(
        &["render", "--method", "bundles", "--two-bounce", "off"],
        &[],
    );
    assert_clean_error(
        &o,
        &["scene `off` not found: --two-bounce is a switch and takes its value after `=` (`--two-bounce=false`)"],
    );
    let o = irad(&["render", "--method", "env", "--shadows", "yes"], &[]);
    assert_clean_error(&o, &["--shadows is a switch", "(`--shadows=true`)"]);
}

/// Values that start with `-` reach irad's checks, which name the flag, the value and what it
/// takes, instead of clap's "unexpected argument '-i'".
#[test]
fn hyphen_values_are_refused_by_flag_and_value() {
    let o = irad(&["render", "--method", "ir", "--clamp", "-inf"], &[]);
    assert_clean_error(
        &o,
        &["--clamp -inf: expected \"auto\" or a finite number >= 0 (--method ir)"],
    );
    let o = irad(
        &["bench", "suite", "--quick", "--list", "--shard", "-1/2"],
        &[],
    );
    let err = stderr(&o);
    assert!(!o.status.success(), "{err}");
    assert!(!err.contains("unexpected argument"), "{err}");
    assert!(
        err.contains("'-1/2' for '--shard <I/N>'") && err.contains("expected I/N with 0 <= I < N"),
        "{err}"
    );
}

/// A setting that does not apply beside the others given is one line naming the flag, its
/// value, what it applies with and what was given.
#[test]
fn a_setting_beside_a_strategy_it_does_not_apply_to_is_refused() {
    let o = irad(
        &[
            "render",
            "--method",
            "env",
            "--light-only",
            "--strategy",
            "latlong",
        ],
        &[],
    );
    assert_clean_error(
        &o,
        &["--light-only true: applies with strategy = \"dynamic\" or \"uniform-faces\", not \"latlong\" (--method env)"],
    );
    let o = irad(&["methods", "env"], &[]);
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(
        out.contains(
            "Only with strategy = \"alpha\" and at most spp (refused beside other values)."
        ),
        "{out}"
    );
}

/// A scene whose BVH traversals pass lavapipe's loop limit (65535 iterations an invocation,
/// then every loop breaks out silently) is refused in the user's words, not rendered wrong:
/// 40000 long slivers through one cube, so every ray's traversal visits most of the tree
/// (tens of thousands of steps; bvh.glsl's LoopCuts). Elsewhere (no limit) it renders.
#[test]
fn a_render_whose_traversals_pass_the_loop_limit_is_refused() {
    let limited = irad::gpu::list_devices()
        .ok()
        .and_then(|d| {
            let i = irad::gpu::device_info::choose(&d, None).ok()?;
            d.into_iter().find(|x| x.index == i)
        })
        .is_some_and(|d| d.driver.contains("llvmpipe"));
    let dir = temp_dir("loop-limit");
    let mut rng = irad::bvh::procedural::Random::new(1, 0);
    let mut obj = String::from("mtllib slivers.mtl\nusemtl grey\n");
    for i in 0..40_000 {
        let a = rng.point_in(glam::Vec3::splat(-1.0), glam::Vec3::splat(1.0));
        let b = -a + rng.point_in(glam::Vec3::splat(-0.1), glam::Vec3::splat(0.1));
        let c = a + 0.001;
        for v in [a, b, c] {
            obj += &format!("v {} {} {}\n", v.x, v.y, v.z);
        }
        obj += &format!("f {} {} {}\n", 3 * i + 1, 3 * i + 2, 3 * i + 3);
    }
    std::fs::write(dir.join("slivers.obj"), obj).unwrap();
    std::fs::write(dir.join("slivers.mtl"), "newmtl grey\nKd 0.5 0.5 0.5\n").unwrap();
    let scene = dir.join("scene.toml");
    std::fs::write(
        &scene,
        "[camera]\nposition = [0, 2, 3]\nlook_at = [0, 0, 0]\nfov_y = 45\nresolution = [16, 16]\n\
         [[mesh]]\nobj = \"slivers.obj\"\n[[light]]\nkind = \"point\"\nposition = [0, 1.5, 0]\n\
         intensity = [3, 3, 3]\n",
    )
    .unwrap();
    let out = dir.join("slivers");
    let o = irad(
        &[
            "render",
            scene.to_str().unwrap(),
            "--spp",
            "1",
            "-o",
            out.to_str().unwrap(),
        ],
        &[],
    );
    if limited {
        assert_clean_error(&o, &["loop limit", "BVH traversal", "simplify the scene"]);
        assert!(!out.with_extension("exr").exists(), "no image is written");
    } else {
        assert!(o.status.success(), "{}", stderr(&o));
    }
    std::fs::remove_dir_all(&dir).ok();
}

/// 5000 coincident quads build a BVH far deeper than the GPU traversal's stack: refused in one
/// line naming the depth (the dependency's own debug assertion panicked here in test builds).
#[test]
fn a_bvh_too_deep_for_the_traversal_is_refused() {
    let dir = temp_dir("deep-bvh");
    let mut obj = String::from("mtllib d.mtl\nusemtl m\n");
    for k in 0..5000 {
        let b = 4 * k + 1;
        obj += &format!(
            "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf {b} {} {} {}\n",
            b + 1,
            b + 2,
            b + 3
        );
    }
    std::fs::write(dir.join("d.obj"), obj).unwrap();
    std::fs::write(dir.join("d.mtl"), "newmtl m\nKd 0.5 0.5 0.5\nKe 1 1 1\n").unwrap();
    let scene = dir.join("scene.toml");
    std::fs::write(
        &scene,
        "[camera]\nposition = [0.5, 0.5, 3]\nlook_at = [0.5, 0.5, 0]\nfov_y = 40\n\
         resolution = [8, 8]\n[[mesh]]\nobj = \"d.obj\"\n",
    )
    .unwrap();
    let out = dir.join("out");
    let o = irad(
        &[
            "render",
            scene.to_str().unwrap(),
            "--spp",
            "1",
            "-o",
            out.to_str().unwrap(),
        ],
        &[],
    );
    assert!(
        stderr(&o).contains("levels deep, over the 32"),
        "{}",
        stderr(&o)
    );
    assert!(
        !o.status.success() && !stderr(&o).contains("panicked"),
        "{}",
        stderr(&o)
    );
    assert!(!dir.join("out.exr").exists());
    std::fs::remove_dir_all(&dir).ok();
}
