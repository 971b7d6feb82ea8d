//! `irad bench suite`: the quick suite writes every output and they agree with each other (the
//! charted points are the CSV's figures); references are cached and never reused stale;
//! shards merge into the results of one whole run; an interrupted suite leaves readable
//! results; bad suite files are one clear error.

use crate::common;

use std::collections::{BTreeMap, BTreeSet};
use std::fs;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use std::time::{Duration, Instant};

use irad::bench::chart;
use irad::bench::suite::file::Suite;
use irad::bench::suite::results::{parse_csv, RunRecord};
use irad::bench::suite::{self, merge, Shard, Status, SuiteOptions, SuiteResults};

fn irad(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_irad"))
        .args(args)
        .env("IRAD_VALIDATE", "1")
        .output()
        .unwrap()
}

fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("irad-bench-suite-{}-{name}", std::process::id()));
    let _ = fs::remove_dir_all(&dir);
    fs::create_dir_all(&dir).unwrap();
    dir
}

/// The CSV as maps from column name to cell, one per row.
fn csv_rows(path: &Path) -> Vec<BTreeMap<String, String>> {
    let rows = parse_csv(&fs::read_to_string(path).unwrap()).unwrap();
    let header = &rows[0];
    rows[1..]
        .iter()
        .map(|row| {
            assert_eq!(row.len(), header.len(), "ragged CSV row {row:?}");
            header.iter().cloned().zip(row.iter().cloned()).collect()
        })
        .collect()
}

fn decode_png(path: &Path) -> (u32, u32) {
    let decoder = png::Decoder::new(std::io::BufReader::new(fs::File::open(path).unwrap()));
    let reader = decoder
        .read_info()
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let info = reader.info();
    (info.width, info.height)
}

/// Every output of a finished suite exists, parses and agrees with results.json; returns it.
fn check_outputs(out: &Path) -> SuiteResults {
    let results = SuiteResults::read(&out.join("results.json")).unwrap();
    let rows = csv_rows(&out.join("results.csv"));
    assert_eq!(rows.len(), results.runs.len());
    for (row, run) in rows.iter().zip(&results.runs) {
        assert_eq!(row["id"], run.id);
        assert_eq!(row["status"], run.status.as_str());
    }
    for scene in results.scenes() {
        let svg = fs::read_to_string(out.join(suite::output::chart_path(&scene))).unwrap();
        let (axes, points) = chart::read_svg(&svg).unwrap();
        // Exactly the ok runs with a positive time and relMSE are charted, at their CSV figures.
        let chartable: Vec<&BTreeMap<String, String>> = rows
            .iter()
            .filter(|r| r["scene"] == scene && r["status"] == "ok")
            .filter(|r| {
                let pos = |k: &str| r[k].parse::<f64>().is_ok_and(|v| v > 0.0);
                pos("gpu_ms") && pos("rel_mse")
            })
            .collect();
        assert_eq!(points.len(), chartable.len(), "{scene}: {points:?}");
        for row in chartable {
            let p = points
                .iter()
                .find(|p| p.run_id == row["id"])
                .unwrap_or_else(|| panic!("{} is not charted", row["id"]));
            assert_eq!(p.x, row["gpu_ms"].parse::<f64>().unwrap(), "{}", row["id"]);
            assert_eq!(p.y, row["rel_mse"].parse::<f64>().unwrap(), "{}", row["id"]);
            assert_eq!(p.series, row["label"]);
            assert_eq!(p.label, row["budget"]);
            let (cx, cy) = axes.to_px(p.x, p.y);
            assert!(
                (cx - p.cx).abs() < 1e-2 && (cy - p.cy).abs() < 1e-2,
                "{p:?}"
            );
            // The bar spans the run's seeds: the lowest and highest relMSE of its images, the
            // mean between them.
            let range = (
                row["rel_mse_min"].parse::<f64>().unwrap(),
                row["rel_mse_max"].parse::<f64>().unwrap(),
            );
            let ((low, high), _) = p.bar.unwrap_or_else(|| panic!("{}: no bar", row["id"]));
            assert_eq!((low, high), range, "{}", row["id"]);
            assert!(low <= p.y && p.y <= high, "{}: {p:?}", row["id"]);
        }
    }
    // The report names every scene and links only images that exist and decode.
    let report = fs::read_to_string(out.join("report.md")).unwrap();
    for scene in results.scenes() {
        assert!(report.contains(&format!("## {scene}")), "{scene}");
    }
    let mut links = 0;
    for part in report.split("](").skip(1) {
        let link = &part[..part.find(')').unwrap()];
        let path = out.join(link);
        assert!(path.exists(), "report links {link}, which is missing");
        if link.ends_with(".png") {
            let (w, h) = decode_png(&path);
            assert!(w > 0 && h > 0);
        }
        links += 1;
    }
    let ok_runs = results
        .runs
        .iter()
        .filter(|r| r.status == Status::Ok)
        .count();
    assert!(
        links >= 2 * ok_runs + results.scenes().len(),
        "{links} links"
    );
    for run in &results.runs {
        if run.status == Status::Ok {
            let m = run.metrics.expect("ok runs are scored");
            assert_eq!(m.nan_inf, 0, "{}", run.id);
            assert_eq!(run.nonfinite_estimates, 0, "{}", run.id);
            assert!(m.rel_mse.is_finite() && run.gpu_ms.is_some(), "{}", run.id);
            if run.flicker_frames >= 2 {
                // 0 only when every frame is identical (a black image, say).
                assert!(
                    run.flicker.is_some_and(|f| f.is_finite() && f >= 0.0),
                    "{}",
                    run.id
                );
            }
            for image in [&run.image, &run.error_map] {
                decode_png(&out.join(image.as_ref().unwrap()));
            }
        } else {
            assert!(
                !run.note.is_empty(),
                "{}: a {:?} run says why",
                run.id,
                run.status
            );
        }
    }
    results
}

#[test]
fn quick_suite_writes_every_output_and_charts_the_csv_figures() {
    let dir = temp_dir("quick");
    let (out, cache) = (dir.join("out"), dir.join("cache"));
    let start = Instant::now();
    let o = irad(&[
        "bench",
        "suite",
        "--quick",
        "-o",
        out.to_str().unwrap(),
        "--cache",
        cache.to_str().unwrap(),
    ]);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{stderr}");
    assert!(
        !stderr.contains("[vulkan "),
        "validation messages: {stderr}"
    );
    eprintln!("quick suite: {:.0} s", start.elapsed().as_secs_f64());
    let results = check_outputs(&out);
    assert!(results.complete);
    assert_eq!(results.runs.len(), results.runs_in_suite);
    // Every built-in method ran on a scene it renders; ir declined the environment-lit scene;
    // the stability scene is in, with lightfield marked as the method expected to fail there.
    let ok = |m: &str| {
        results
            .runs
            .iter()
            .any(|r| r.method == m && r.status == Status::Ok)
    };
    for method in irad::methods::Registry::builtin().names() {
        assert!(ok(method), "{method} did not run");
    }
    assert!(results.runs.iter().any(|r| r.method == "ir"
        && r.status == Status::Declined
        && r.note.contains("environment")));
    let failure_scenes: Vec<&String> = results
        .references
        .iter()
        .filter(|(_, r)| !r.expected_to_fail.is_empty())
        .map(|(s, _)| s)
        .collect();
    assert!(!failure_scenes.is_empty(), "{failure_scenes:?}");
    let expected: Vec<&RunRecord> = results
        .runs
        .iter()
        .filter(|r| failure_scenes.contains(&&r.scene) && r.method == "lightfield")
        .collect();
    assert!(!expected.is_empty() && expected.iter().all(|r| r.expected_failure));
    // The path-traced scenes are judged against their stored converged references, far below
    // the runs' error (no ‡ there).
    for scene in ["cornell-box", "glossy-env"] {
        let r = &results.references[scene];
        assert!(r.cache.contains("converged"), "{scene}: {}", r.cache);
        assert!(
            r.rel_mse.is_some_and(|e| e < 1e-3),
            "{scene}: {:?}",
            r.rel_mse
        );
    }
    assert!(results.runs.iter().any(|r| r.pareto));
    // report.html: every scored run's row and image, each scene's viewer.
    let html = fs::read_to_string(out.join("report.html")).unwrap();
    let start = html.find("const IRAD_DATA = ").unwrap() + 18;
    let end = start + html[start..].find(";\n").unwrap();
    let data: serde_json::Value = serde_json::from_str(&html[start..end]).unwrap();
    for (k, scene) in results.scenes().iter().enumerate() {
        let viewer = &data[format!("scene{k}")];
        let names: Vec<&str> = viewer["names"]
            .as_array()
            .unwrap()
            .iter()
            .map(|n| n.as_str().unwrap())
            .collect();
        assert_eq!(names[0], "reference", "{scene}");
        assert_eq!(
            viewer["frames"][0]["images"].as_array().unwrap().len(),
            names.len()
        );
        for r in results
            .runs
            .iter()
            .filter(|r| &r.scene == scene && r.status == Status::Ok)
        {
            let name = format!("{} {}", r.label, r.budget);
            assert!(html.contains(&format!("data-image=\"{name}\"")), "{name}");
            assert!(names.contains(&name.as_str()), "{name}'s image");
        }
    }
    assert_eq!(
        html.matches("<div class=\"viewer\">").count(),
        results.scenes().len()
    );
    // The declined run is listed with its reason.
    assert!(html.contains("Runs with no image:"));
    assert!(html.contains("<li>ir ") && html.contains(": declined, "));
    // ...and the page in a real browser (tests/browser.rs).
    crate::browser::check_report(&out.join("report.html"), results.scenes().len());
    // Every reference knows its own error (from its halves), and the report says it.
    let report = fs::read_to_string(out.join("report.md")).unwrap();
    for (scene, r) in &results.references {
        let e = r.rel_mse.unwrap_or(f64::NAN);
        assert!(e.is_finite() && e > 0.0, "{scene}: {e}");
        assert!(report.contains(&format!("{e:.3e}")), "{scene}");
    }
    let _ = fs::remove_dir_all(&dir);
}

/// A time budget: the run calibrates its count (frames; the reference's spp) to fill the
/// GPU time, records it, and renders exactly as a fixed budget of that count does; the report
/// tables the scene's runs at equal time with the home method marked.
#[test]
fn a_time_budget_records_its_count_and_renders_as_that_count_does() {
    let dir = temp_dir("time");
    let cache = dir.join("cache");
    let text = r#"
name = "time"
width = 16
warmup = 0
repeats = 1
flicker_frames = 0
[reference]
spp = 32
[[scene]]
path = "embedded:cornell-box"
home = ["ir"]
[[method]]
method = "reference"
label = "pt"
budgets = [{ time_ms = 40 }]
[[method]]
method = "ir"
params = { vpls = 8 }
budgets = [{ time_ms = 80 }]
"#;
    let suite = Suite::parse("time.toml", text, &scenes_dir()).unwrap();
    common::with_gpu(|ctx| {
        let timed = run_suite(ctx, &suite, &dir.join("timed"), &cache, Shard::WHOLE);
        let mut fixed_text = text.to_string();
        for (run, key) in timed.runs.iter().zip(["spp", "frames"]) {
            assert_eq!(run.status, Status::Ok, "{}", run.note);
            let count = run
                .calibrated_count
                .expect("a time budget records its count");
            assert!(count >= 1);
            assert_eq!(run.parameters[key], serde_json::json!(count), "{}", run.id);
            assert!(!run.calibration.is_empty() && run.calibration.iter().all(|t| t.ms > 0.0));
            let budget = format!("{{ time_ms = {} }}", run.time_ms.unwrap());
            fixed_text = fixed_text.replacen(&budget, &format!("{{ {key} = {count} }}"), 1);
        }
        assert!(timed.runs[1].home && !timed.runs[0].home);
        let fixed = Suite::parse("time.toml", &fixed_text, &scenes_dir()).unwrap();
        let counted = run_suite(ctx, &fixed, &dir.join("counted"), &cache, Shard::WHOLE);
        // The same bits: every error figure equal.
        let metrics = |r: &SuiteResults| r.runs.iter().map(|r| r.metrics).collect::<Vec<_>>();
        assert_eq!(metrics(&timed), metrics(&counted));
        assert!(metrics(&timed).iter().all(|m| m.is_some()));
        let rows = csv_rows(&dir.join("timed").join("results.csv"));
        assert_eq!(
            rows[1]["calibrated_count"],
            timed.runs[1].calibrated_count.unwrap().to_string()
        );
        assert_eq!(rows[1]["time_ms"], "80");
        let report = fs::read_to_string(dir.join("timed").join("report.md")).unwrap();
        assert!(report.contains("Equal time, 80 GPU ms"), "{report}");
        assert!(
            report.contains("| ⌂ | ir |") && report.contains("speed vs pt"),
            "{report}"
        );
    });
    let _ = fs::remove_dir_all(&dir);
}

/// A time budget no count can meet (a microsecond) is recorded as missed, with the time the
/// run took, in the JSON, the CSV and the report (a mark and a footnote).
#[test]
fn a_time_budget_that_cannot_be_met_is_marked_missed() {
    let dir = temp_dir("missed");
    let text = r#"
name = "missed"
width = 8
warmup = 0
repeats = 1
flicker_frames = 0
[reference]
spp = 8
[[scene]]
path = "embedded:cornell-box"
[[method]]
method = "reference"
label = "pt"
budgets = [{ time_ms = 0.001 }, { spp = 1 }]
"#;
    let suite = Suite::parse("missed.toml", text, &scenes_dir()).unwrap();
    let out = dir.join("out");
    common::with_gpu(|ctx| {
        let results = run_suite(ctx, &suite, &out, &dir.join("cache"), Shard::WHOLE);
        let (timed, fixed) = (&results.runs[0], &results.runs[1]);
        assert_eq!(timed.status, Status::Ok, "{}", timed.note);
        assert_eq!(timed.calibrated_count, Some(1));
        assert!(timed.budget_missed && timed.gpu_ms.unwrap() > 0.001);
        assert!(!fixed.budget_missed);
        let rows = csv_rows(&out.join("results.csv"));
        assert_eq!(rows[0]["budget_missed"], "true");
        assert_eq!(rows[1]["budget_missed"], "false");
        let report = fs::read_to_string(out.join("report.md")).unwrap();
        let gpu = format!("{:.2}{}", timed.gpu_ms.unwrap(), suite::report::MISSED_MARK);
        assert!(report.contains(&gpu), "{report}");
        assert!(
            report.contains("† Time budget missed: pt time_ms=0.001 took"),
            "{report}"
        );
    });
    let _ = fs::remove_dir_all(&dir);
}

const TINY_SUITE: &str = r#"
name = "tiny"
width = 16
warmup = 0
repeats = 2
[reference]
spp = 32
[[scene]]
path = "embedded:cornell-box"
[[scene]]
path = "point-light-plane/scene.toml"
[[method]]
method = "reference"
label = "pt"
budgets = [{ spp = 1 }, { spp = 4 }]
[[method]]
method = "ir"
budgets = [{ vpls = 8, frames = 1 }]
"#;

fn scenes_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes")
}

/// Copies the point-light plane scene into `to` (a scene folder of a test's own: editing it
/// changes its content hash, and converged references are written beside it).
fn copy_plane_scene(to: &Path) {
    fs::create_dir_all(to).unwrap();
    for f in [
        "scene.toml",
        "point-light-plane.obj",
        "point-light-plane.mtl",
    ] {
        fs::copy(scenes_dir().join("point-light-plane").join(f), to.join(f)).unwrap();
    }
}

/// A suite of the copied plane (`plane/scene.toml`) with an 8-sample reference; NAME is
/// replaced by the suite's name.
const PLANE_SUITE: &str = r#"
name = "NAME"
width = 8
warmup = 0
repeats = 1
[reference]
spp = 8
[[scene]]
path = "plane/scene.toml"
[[method]]
method = "reference"
budgets = [{ spp = 1 }]
"#;

fn run_suite(
    ctx: &irad::gpu::Context,
    suite: &Suite,
    out: &Path,
    cache: &Path,
    shard: Shard,
) -> SuiteResults {
    let options = SuiteOptions {
        out: out.to_path_buf(),
        cache: cache.to_path_buf(),
        shard,
        stop: None,
        references_only: false,
    };
    suite::run(ctx, suite, &options, |_| {}).unwrap()
}

/// Figures that depend only on the bits rendered (not on timing).
fn figures(results: &SuiteResults) -> Vec<(String, Option<irad::image::Metrics>, Option<f64>)> {
    results
        .runs
        .iter()
        .map(|r| (r.id.clone(), r.metrics, r.flicker))
        .collect()
}

#[test]
fn shards_merge_into_the_whole_suite() {
    let dir = temp_dir("shards");
    let cache = dir.join("cache");
    let suite = Suite::parse("tiny.toml", TINY_SUITE, &scenes_dir()).unwrap();
    assert_eq!(suite.runs.len(), 6);
    common::with_gpu(|ctx| {
        let whole = run_suite(ctx, &suite, &dir.join("whole"), &cache, Shard::WHOLE);
        let parts: Vec<PathBuf> = (0..3).map(|i| dir.join(format!("part{i}"))).collect();
        for (i, part) in parts.iter().enumerate() {
            let r = run_suite(ctx, &suite, part, &cache, Shard { index: i, count: 3 });
            assert_eq!(r.runs.len(), 2);
            assert!(r.runs.iter().all(|run| run.index % 3 == i));
        }
        // Parts in any order give the whole suite, bit for bit in every figure.
        let merged_dir = dir.join("merged");
        let reversed: Vec<PathBuf> = parts.iter().rev().cloned().collect();
        let merged = merge::merge(&reversed, &merged_dir, false).unwrap();
        assert!(merged.complete && merged.shard.is_none());
        assert_eq!(figures(&merged), figures(&whole));
        assert_eq!(check_outputs(&merged_dir), merged);
        check_outputs(&dir.join("whole"));
        // Missing parts leave it incomplete; a part given twice, or another suite, is refused.
        let partial = merge::merge(&parts[..2], &dir.join("partial"), false).unwrap();
        assert!(!partial.complete);
        let twice = merge::merge(
            &[parts[0].clone(), parts[0].clone()],
            &dir.join("twice"),
            false,
        );
        assert!(twice.unwrap_err().to_string().contains("in both"));
        let other = Suite::parse(
            "other.toml",
            &TINY_SUITE.replace("spp = 32", "spp = 33"),
            &scenes_dir(),
        )
        .unwrap();
        run_suite(
            ctx,
            &other,
            &dir.join("other"),
            &cache,
            Shard { index: 1, count: 3 },
        );
        let mixed = merge::merge(
            &[parts[0].clone(), dir.join("other")],
            &dir.join("mixed"),
            false,
        );
        assert!(mixed.unwrap_err().to_string().contains("same suite"));
        // Parts from another device are refused unless allowed, then charted apart.
        let moved = dir.join("moved");
        fs::create_dir_all(moved.join("images")).unwrap();
        let mut elsewhere = SuiteResults::read(&parts[2].join("results.json")).unwrap();
        elsewhere.device = "Another GPU".into();
        for run in &mut elsewhere.runs {
            run.device = "Another GPU".into();
        }
        fs::write(moved.join("results.json"), elsewhere.json()).unwrap();
        for entry in fs::read_dir(parts[2].join("images")).unwrap() {
            let entry = entry.unwrap();
            fs::copy(entry.path(), moved.join("images").join(entry.file_name())).unwrap();
        }
        let two = [parts[0].clone(), parts[1].clone(), moved];
        let e = merge::merge(&two, &dir.join("devices"), false)
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("Another GPU") && e.contains("--allow-mixed-devices"),
            "{e}"
        );
        let allowed = merge::merge(&two, &dir.join("devices"), true).unwrap();
        assert!(allowed.device.starts_with("mixed"));
        let svg = fs::read_to_string(
            dir.join("devices")
                .join(suite::output::chart_path("cornell-box")),
        )
        .unwrap();
        let (_, points) = chart::read_svg(&svg).unwrap();
        assert!(
            points.iter().any(|p| p.series.contains("(Another GPU)")),
            "{points:?}"
        );
    });
    let _ = fs::remove_dir_all(&dir);
}

#[test]
fn references_are_cached_and_never_reused_stale() {
    let dir = temp_dir("cache");
    let cache = dir.join("cache");
    // A scene folder of our own, so editing it changes its content hash.
    let scene_dir = dir.join("scenes/plane");
    copy_plane_scene(&scene_dir);
    let text = &PLANE_SUITE.replace("NAME", "cache");
    let entries = |cache: &Path| -> Vec<PathBuf> {
        let mut found = Vec::new();
        for scene in fs::read_dir(cache).unwrap() {
            for key in fs::read_dir(scene.unwrap().path()).unwrap() {
                found.push(key.unwrap().path());
            }
        }
        found.sort();
        found
    };
    common::with_gpu(|ctx| {
        let base = dir.join("scenes");
        let original = Suite::parse("cache.toml", text, &base).unwrap();
        let first = run_suite(ctx, &original, &dir.join("a"), &cache, Shard::WHOLE);
        let entry = entries(&cache);
        assert_eq!(entry.len(), 1);
        let record = entry[0].join("reference.json");
        let written = fs::metadata(&record).unwrap().modified().unwrap();
        // The same suite again reuses the reference: same figures, file untouched.
        let again = run_suite(ctx, &original, &dir.join("b"), &cache, Shard::WHOLE);
        assert_eq!(figures(&again), figures(&first));
        assert_eq!(fs::metadata(&record).unwrap().modified().unwrap(), written);
        // Other reference settings: a second entry.
        let more = Suite::parse("cache.toml", &text.replace("spp = 8", "spp = 9"), &base).unwrap();
        run_suite(ctx, &more, &dir.join("c"), &cache, Shard::WHOLE);
        assert_eq!(entries(&cache).len(), 2);
        // An edited scene (a brighter light) has another content hash: a new reference.
        let toml_path = scene_dir.join("scene.toml");
        let scene_text = fs::read_to_string(&toml_path).unwrap();
        let edited =
            scene_text.replacen("intensity = [", "intensity = [2.0, 2.0, 2.0]\n# was [", 1);
        assert_ne!(edited, scene_text);
        fs::write(&toml_path, edited).unwrap();
        let edited = Suite::parse("cache.toml", text, &base).unwrap();
        let brighter = run_suite(ctx, &edited, &dir.join("d"), &cache, Shard::WHOLE);
        assert_eq!(entries(&cache).len(), 3);
        assert_ne!(figures(&brighter), figures(&first));
        // A cache entry whose record does not match its key (tampered, or a half-written
        // entry from another version) is rendered again, not trusted.
        let record = entries(&cache)[0].join("reference.json");
        let tampered =
            fs::read_to_string(&record)
                .unwrap()
                .replacen("\"seed\": ", "\"seed\": 1", 1);
        fs::write(&record, tampered).unwrap();
        let key_dirs = entries(&cache);
        for (i, suite) in [&original, &more, &edited].into_iter().enumerate() {
            run_suite(ctx, suite, &dir.join(format!("e{i}")), &cache, Shard::WHOLE);
        }
        assert_eq!(entries(&cache), key_dirs);
        let fixed = fs::read_to_string(&record).unwrap();
        assert!(
            !fixed.contains("\"seed\": 1"),
            "the stale record was reused: {fixed}"
        );
    });
    let _ = fs::remove_dir_all(&dir);
}

#[test]
fn interrupted_suite_leaves_readable_results() {
    let dir = temp_dir("interrupt");
    let suite_path = dir.join("slow.toml");
    // Enough runs that the suite is still going when the first result is on disk.
    let budgets: Vec<String> = (1..=12).map(|i| format!("{{ spp = {} }}", 8 * i)).collect();
    fs::write(
        &suite_path,
        format!(
            "name = \"slow\"\nwidth = 32\nwarmup = 0\nrepeats = 2\n[reference]\nspp = 16\n[[scene]]\npath = \"embedded:cornell-box\"\n[[method]]\nmethod = \"reference\"\nbudgets = [{}]\n",
            budgets.join(", ")
        ),
    )
    .unwrap();
    let out = dir.join("out");
    let mut child = Command::new(env!("CARGO_BIN_EXE_irad"))
        .args(["bench", "suite", suite_path.to_str().unwrap(), "-o"])
        .arg(&out)
        .arg("--cache")
        .arg(dir.join("cache"))
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::null())
        .spawn()
        .unwrap();
    let deadline = Instant::now() + Duration::from_secs(120);
    loop {
        let runs = SuiteResults::read(&out.join("results.json"))
            .map(|r| r.runs.len())
            .unwrap_or(0);
        if runs >= 1 {
            break;
        }
        assert!(Instant::now() < deadline, "no result after 120 s");
        std::thread::sleep(Duration::from_millis(20));
    }
    // Ctrl-C.
    let status = Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status()
        .unwrap();
    assert!(status.success());
    let exit = child.wait().unwrap();
    let results = check_outputs(&out);
    assert!(
        !exit.success(),
        "the suite finished before it was interrupted"
    );
    assert!(
        !results.complete && results.runs.len() < 12,
        "{}",
        results.runs.len()
    );
    assert!(fs::read_to_string(out.join("report.md"))
        .unwrap()
        .contains("incomplete"));
    // The same command again resumes: it says so, keeps the recorded runs as they were and
    // renders the rest.
    let o = irad(&[
        "bench",
        "suite",
        suite_path.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
        "--cache",
        dir.join("cache").to_str().unwrap(),
    ]);
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let kept = results.runs.len();
    assert!(
        text.contains(&format!("{kept} of 12 runs recorded there are kept")),
        "{text}"
    );
    let finished = check_outputs(&out);
    assert!(finished.complete && finished.runs.len() == 12);
    // As recorded (the Pareto marks are recomputed over all runs).
    let measured = |r: &suite::RunRecord| (r.id.clone(), r.metrics, r.gpu_ms, r.wall_ms);
    assert!(finished.runs[..kept]
        .iter()
        .map(measured)
        .eq(results.runs.iter().map(measured)));
    let _ = fs::remove_dir_all(&dir);
}

/// Two runs that take milliseconds each.
const SMALL_SUITE: &str = r#"
name = "small"
width = 8
warmup = 0
repeats = 1
flicker_frames = 0
[reference]
spp = 8
[[scene]]
path = "embedded:cornell-box"
[[method]]
method = "reference"
label = "pt"
budgets = [{ spp = 1 }, { spp = 2 }]
"#;

fn run_suite_events(
    ctx: &irad::gpu::Context,
    suite: &Suite,
    out: &Path,
    cache: &Path,
    shard: Shard,
    events: &mut Vec<String>,
) -> anyhow::Result<SuiteResults> {
    let options = SuiteOptions {
        out: out.to_path_buf(),
        cache: cache.to_path_buf(),
        shard,
        stop: None,
        references_only: false,
    };
    suite::run(ctx, suite, &options, |e| match e {
        suite::Event::Resumed { kept, .. } => events.push(format!("resumed {kept:?}")),
        suite::Event::StaleLock { holder } => events.push(format!("stale {holder}")),
        _ => {}
    })
}

/// A folder a suite (or a merge) writes is locked: a second writer is refused with the folder
/// and the holder named; a lock left by a process that is gone is taken over with a note, and
/// the lock file is gone once the suite is done.
#[test]
fn a_suite_folder_is_locked_while_written() {
    let dir = temp_dir("lock");
    let (out, cache) = (dir.join("out"), dir.join("cache"));
    let suite = Suite::parse("small.toml", SMALL_SUITE, &scenes_dir()).unwrap();
    let held = suite::output::lock(&out, &mut |_| panic!("no stale lock here")).unwrap();
    let pid = format!("pid {}", std::process::id());
    common::with_gpu(|ctx| {
        let mut events = Vec::new();
        let e = run_suite_events(ctx, &suite, &out, &cache, Shard::WHOLE, &mut events)
            .unwrap_err()
            .to_string();
        assert!(e.contains(out.to_str().unwrap()) && e.contains(&pid), "{e}");
        assert!(!out.join("results.json").exists());
        drop(held);
        assert!(!out.join(irad::lock::LOCK_FILE).exists());
        // A lock file whose process is gone (no flock held on it).
        fs::write(out.join(irad::lock::LOCK_FILE), "pid 4000000 on gone\n").unwrap();
        let results =
            run_suite_events(ctx, &suite, &out, &cache, Shard::WHOLE, &mut events).unwrap();
        assert!(results.complete);
        assert_eq!(events, ["stale irad (pid 4000000 on gone)"]);
        assert!(!out.join(irad::lock::LOCK_FILE).exists());
        // A merge into a locked folder is refused too, and writes nothing there.
        let merged = dir.join("merged");
        let held = suite::output::lock(&merged, &mut |_| panic!("no stale lock here")).unwrap();
        let e = merge::merge(std::slice::from_ref(&out), &merged, false)
            .unwrap_err()
            .to_string();
        assert!(
            e.contains(merged.to_str().unwrap()) && e.contains(&pid),
            "{e}"
        );
        assert!(!merged.join("results.json").exists());
        drop(held);
        merge::merge(std::slice::from_ref(&out), &merged, false).unwrap();
    });
    let _ = fs::remove_dir_all(&dir);
}

/// Running an interrupted suite again into its folder keeps the runs it recorded (their
/// records untouched, not rendered again) and renders the rest; a finished one is measured
/// afresh; another suite's folder is refused and left as it was.
#[test]
fn an_interrupted_suite_resumes_with_its_runs_kept() {
    let dir = temp_dir("resume");
    let (out, cache) = (dir.join("out"), dir.join("cache"));
    let suite = Suite::parse("small.toml", SMALL_SUITE, &scenes_dir()).unwrap();
    common::with_gpu(|ctx| {
        let mut events = Vec::new();
        let whole = run_suite_events(ctx, &suite, &out, &cache, Shard::WHOLE, &mut events).unwrap();
        assert_eq!(whole.runs.len(), 2);
        // As an interruption after the first run leaves it, with a mark on the kept record.
        let mut cut = whole.clone();
        cut.runs.truncate(1);
        cut.complete = false;
        cut.runs[0].wall_ms = Some(123456.0);
        fs::write(out.join("results.json"), cut.json()).unwrap();
        let resumed =
            run_suite_events(ctx, &suite, &out, &cache, Shard::WHOLE, &mut events).unwrap();
        assert_eq!(events, ["resumed [0]"]);
        assert!(resumed.complete);
        assert_eq!(
            resumed.runs[0].wall_ms,
            Some(123456.0),
            "run 0 rendered again"
        );
        assert_eq!(figures(&resumed), figures(&whole));
        assert_eq!(check_outputs(&out), resumed);
        // Finished: run again, measured afresh.
        let again = run_suite_events(ctx, &suite, &out, &cache, Shard::WHOLE, &mut events).unwrap();
        assert_ne!(again.runs[0].wall_ms, Some(123456.0));
        assert_eq!(events.len(), 1);
        // Another suite (other reference settings) into this folder: refused, folder kept.
        let before = fs::read(out.join("results.json")).unwrap();
        let other = Suite::parse(
            "small.toml",
            &SMALL_SUITE.replace("spp = 8", "spp = 9"),
            &scenes_dir(),
        )
        .unwrap();
        let e = run_suite_events(ctx, &other, &out, &cache, Shard::WHOLE, &mut events)
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("holds the results of suite `small`") && e.contains(out.to_str().unwrap()),
            "{e}"
        );
        assert_eq!(fs::read(out.join("results.json")).unwrap(), before);
        check_outputs(&out);
    });
    let _ = fs::remove_dir_all(&dir);
}

/// `bench merge` checks every part before writing: a part without images/, or missing an
/// image its results name, is refused and nothing is written (an earlier merge stays whole);
/// a folder holding other files is not replaced.
#[test]
fn merge_refuses_a_broken_part_and_writes_nothing() {
    let dir = temp_dir("merge-broken");
    let cache = dir.join("cache");
    let suite = Suite::parse("small.toml", SMALL_SUITE, &scenes_dir()).unwrap();
    let parts: Vec<PathBuf> = (0..2).map(|i| dir.join(format!("part{i}"))).collect();
    common::with_gpu(|ctx| {
        for (i, part) in parts.iter().enumerate() {
            run_suite(ctx, &suite, part, &cache, Shard { index: i, count: 2 });
        }
    });
    let merged = dir.join("merged");
    let listing = |d: &Path| -> BTreeSet<String> {
        fs::read_dir(d)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect()
    };
    let with = |mut names: BTreeSet<String>, name: &str| {
        names.insert(name.to_string());
        names
    };
    let top = listing(&dir);
    fs::rename(parts[1].join("images"), dir.join("aside")).unwrap();
    let e = merge::merge(&parts, &merged, false)
        .unwrap_err()
        .to_string();
    assert!(e.contains("part1") && e.contains("images/"), "{e}");
    assert_eq!(listing(&dir), with(top.clone(), "aside"));
    // A whole merge, then one with an image missing: the first stays as it was.
    fs::rename(dir.join("aside"), parts[1].join("images")).unwrap();
    let whole = merge::merge(&parts, &merged, false).unwrap();
    assert!(whole.complete);
    let before = fs::read(merged.join("results.json")).unwrap();
    let image = whole.runs[1].image.clone().unwrap();
    fs::remove_file(parts[1].join(&image)).unwrap();
    let e = merge::merge(&parts, &merged, false)
        .unwrap_err()
        .to_string();
    assert!(e.contains(&image), "{e}");
    assert_eq!(fs::read(merged.join("results.json")).unwrap(), before);
    check_outputs(&merged);
    assert_eq!(
        listing(&dir),
        with(top, "merged"),
        "a temporary folder was left"
    );
    // Not a suite's folder: refused.
    fs::copy(merged.join(&image), parts[1].join(&image)).unwrap();
    let e = merge::merge(&parts, &dir, false).unwrap_err().to_string();
    assert!(e.contains("not a suite output"), "{e}");
    let _ = fs::remove_dir_all(&dir);
}

#[test]
fn every_suite_file_loads_and_the_stability_suite_has_every_failure_scene() {
    let mut suites = vec![scenes_dir().join("failure/suite.toml")];
    for entry in fs::read_dir(scenes_dir().join("suites")).unwrap() {
        suites.push(entry.unwrap().path());
    }
    // A generated family (scale.toml's halls of up to 2^20 lights: minutes of python and tens
    // of seconds to load) is checked at two small counts instead, generated into a scratch
    // folder; everything else in the file is as written.
    let python3 = std::process::Command::new("python3")
        .arg("--version")
        .output()
        .is_ok_and(|o| o.status.success());
    assert!(
        python3 || std::env::var("CI").is_err(),
        "python3 is not installed"
    );
    let generated = temp_dir("every-suite-generated");
    for path in &suites {
        let text = fs::read_to_string(path).unwrap();
        // A generated scene needs python3 (CI has it; elsewhere the file is left out without it).
        if text.contains("generated:") && !python3 {
            eprintln!("note: python3 not found; {} not loaded", path.display());
            continue;
        }
        // Every scene's light counts, wherever the file writes them, become [16, 64].
        let mut table: toml::Table = toml::from_str(&text).unwrap();
        if let Some(toml::Value::Array(scenes)) = table.get_mut("scene") {
            for scene in scenes.iter_mut().filter_map(|s| s.as_table_mut()) {
                if scene.contains_key("lights") {
                    scene.insert("lights".into(), toml::Value::try_from([16, 64]).unwrap());
                }
            }
        }
        let small = toml::to_string(&table).unwrap();
        let suite = Suite::parse_generating(
            &path.display().to_string(),
            &small,
            path.parent().unwrap(),
            irad::methods::Registry::builtin(),
            &generated,
        )
        .unwrap_or_else(|e| panic!("{e}"));
        assert!(!suite.runs.is_empty(), "{}", path.display());
    }
    let _ = fs::remove_dir_all(&generated);
    let stability = Suite::load(&scenes_dir().join("failure/suite.toml")).unwrap();
    let in_suite: Vec<&str> = stability
        .scenes
        .iter()
        .map(|s| s.scene.name.as_str())
        .collect();
    for entry in fs::read_dir(scenes_dir().join("failure")).unwrap() {
        let path = entry.unwrap().path();
        if path.join("scene.toml").exists() {
            let name = path.file_name().unwrap().to_str().unwrap().to_string();
            assert!(
                in_suite.contains(&name.as_str()),
                "{name} is not in the stability suite"
            );
        }
    }
    // Every method irad has runs on every stability scene it does not decline.
    for s in &stability.scenes {
        for method in irad::methods::Registry::builtin().names() {
            assert!(
                stability.runs.iter().any(|r| r.method.name() == method
                    && stability.scenes[r.scene].scene.name == s.scene.name),
                "{method} does not run on {}",
                s.scene.name
            );
        }
    }
}

#[test]
fn bad_suite_files_name_file_field_and_value() {
    let parse = |text: &str| {
        Suite::parse("s.toml", text, &scenes_dir())
            .map(|_| ())
            .unwrap_err()
            .to_string()
    };
    let with = |from: &str, to: &str| {
        let t = TINY_SUITE.replacen(from, to, 1);
        assert_ne!(t, TINY_SUITE, "{from}");
        parse(&t)
    };
    let e = with("warmup = 0", "warmup = 0\ncolour = 1");
    assert!(e.starts_with("s.toml: ") && e.contains("colour"), "{e}");
    let e = with("vpls = 8", "vpls = 0");
    assert!(
        e.contains("s.toml: method[1].budgets[0]: ir: vpls = 0: must be in"),
        "{e}"
    );
    let e = with("method = \"ir\"", "method = \"bidir\"");
    assert!(e.contains("unknown method `bidir`"), "{e}");
    let e = with("label = \"pt\"", "label = \"ir\"");
    assert!(
        e.contains("method[1].label = \"ir\": used by an earlier"),
        "{e}"
    );
    let e = with(
        "budgets = [{ vpls",
        "scenes = [\"attic\"]\nbudgets = [{ vpls",
    );
    assert!(
        e.contains("method[1].scenes = \"attic\": not the name"),
        "{e}"
    );
    let e = with("point-light-plane/scene.toml", "nowhere/scene.toml");
    assert!(
        e.contains("s.toml: scene[1].path = \"nowhere/scene.toml\"") && e.contains("nowhere"),
        "{e}"
    );
    let e = with("width = 16", "width = 0");
    assert!(e.contains("s.toml: width = 0: must be in"), "{e}");
    let e = with(
        "path = \"embedded:cornell-box\"",
        "path = \"embedded:cornell-box\"\nresolution = [0, 16]",
    );
    assert!(e.contains("scene[0].resolution = [0, 16]"), "{e}");
    // An array too long is refused, not cut to its first two numbers.
    let e = with(
        "path = \"embedded:cornell-box\"",
        "path = \"embedded:cornell-box\"\nresolution = [16, 16, 3]",
    );
    assert!(
        e.contains("invalid length 3") && e.contains("resolution"),
        "{e}"
    );
    let e = with("spp = 32", "spp = 32\nseed = 2");
    assert!(
        e.contains("reference.seed = 2: the reference of scene[0] would share"),
        "{e}"
    );
    let e = with(
        "budgets = [{ spp = 1 }, { spp = 4 }]",
        "budgets = [{ spp = 4 }, { spp = 4, max_depth = 1024 }]",
    );
    assert!(e.contains("the same settings as budget"), "{e}");
    let e = with("name = \"tiny\"", "name = \"..\"");
    assert!(e.contains("name = \"..\""), "{e}");
    let e = with("budgets = [{ vpls", "scenes = []\nbudgets = [{ vpls");
    assert!(e.contains("method[1].scenes = []"), "{e}");
    // A cause is said once.
    let e = with("vpls = 8", "vpls = 0");
    assert_eq!(e.matches("must be in").count(), 1, "{e}");
    let e = with(
        "budgets = [{ spp = 1 }, { spp = 4 }]",
        "params = { spp = 2 }\nbudgets = [{ spp = 1 }]",
    );
    assert!(
        e.contains("method[0].budgets[0].spp = 1: also set in params"),
        "{e}"
    );
    let e = with(
        "{ vpls = 8, frames = 1 }",
        "{ vpls = 8, frames = 1, time_ms = 500 }",
    );
    assert!(
        e.contains("method[1].budgets[0].frames = 1: a time_ms budget calibrates frames"),
        "{e}"
    );
    let e = with("{ spp = 1 }", "{ time_ms = 0 }");
    assert!(
        e.contains("method[0].budgets[0].time_ms = 0: must be GPU milliseconds"),
        "{e}"
    );
    let e = with(
        "path = \"embedded:cornell-box\"",
        "path = \"embedded:cornell-box\"\nhome = [\"bidir\"]",
    );
    assert!(
        e.contains("scene[0].home = \"bidir\": not the label"),
        "{e}"
    );
    let e = with("budgets = [{ vpls = 8, frames = 1 }]", "budgets = []");
    assert!(e.contains("method[1].budgets = []"), "{e}");
    // The CLI prints it as one error line, no panic.
    let o = irad(&["bench", "suite", "/nonexistent/suite.toml"]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        !o.status.success() && err.starts_with("error: /nonexistent/suite.toml: cannot read it"),
        "{err}"
    );
    assert!(!err.contains("panicked"), "{err}");
}

/// `irad bench references` (converged.rs): chunks stopped and resumed give the same bits as
/// one uninterrupted run; the record counts every sample and its relMSE is the halves'; the
/// suite reads the stored reference in place of the cache when the key matches and it has at
/// least the samples asked for, and falls back to the cache otherwise.
#[test]
fn converged_references_resume_bit_exactly_and_the_suite_uses_them() {
    use irad::bench::suite::converged::{self, ExtendOptions, Progress};
    use irad::methods::Renderers;
    use irad::scene::gpu::GpuScene;
    use std::sync::atomic::{AtomicBool, Ordering};

    let dir = temp_dir("converged");
    let text = &PLANE_SUITE.replace("NAME", "converged");
    common::with_gpu(|ctx| {
        let renderers = Renderers::default();
        // Stops after `chunks` chunks in all (the record's count, so a resumed run stops at
        // the same total).
        let extend = |base: &Path, chunks: u32| {
            let suite = Suite::parse("converged.toml", text, base).unwrap();
            let s = &suite.scenes[0];
            let gpu = GpuScene::upload(ctx, &s.scene).unwrap();
            let stop = AtomicBool::new(false);
            let options = ExtendOptions {
                target_rel_mse: 1e-12,
                deadline: None,
                chunk_spp: 3,
                stop: Some(&stop),
            };
            converged::extend(
                ctx,
                &renderers,
                &s.scene,
                &gpu,
                &s.reference,
                &options,
                |e| {
                    if let Progress::Saved { record, .. } = e {
                        if record.chunks >= chunks {
                            stop.store(true, Ordering::SeqCst);
                        }
                    }
                },
            )
            .unwrap()
        };
        let (whole, parts) = (dir.join("whole"), dir.join("parts"));
        copy_plane_scene(&whole.join("plane"));
        copy_plane_scene(&parts.join("plane"));
        let straight = extend(&whole, 5);
        extend(&parts, 2);
        let resumed = extend(&parts, 5);
        assert_eq!(straight.record.spp, [9, 6]);
        assert_eq!(resumed.record.spp, straight.record.spp);
        assert_eq!(resumed.record.chunks, 5);
        assert_eq!(resumed.record.sessions.len(), 2);
        for (a, b) in resumed.halves.iter().zip(&straight.halves) {
            let bits = |i: &irad::image::Image| -> Vec<u32> {
                i.pixels.iter().flatten().map(|v| v.to_bits()).collect()
            };
            assert_eq!(
                bits(a),
                bits(b),
                "a resumed run differs from an uninterrupted one"
            );
        }
        let (image, rel_mse) = resumed.image();
        assert_eq!(resumed.record.rel_mse, Some(rel_mse));
        assert!(image.pixels.iter().flatten().all(|v| v.is_finite()));
        // Only the last halves are kept.
        let files: Vec<_> = fs::read_dir(&resumed.dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().into_string().unwrap())
            .collect();
        assert_eq!(files.len(), 2, "{files:?}");
        // The suite reads it (8 spp asked, 15 stored) instead of rendering into the cache.
        let suite = Suite::parse("converged.toml", text, &parts).unwrap();
        let cache = dir.join("cache");
        let used = run_suite(ctx, &suite, &dir.join("a"), &cache, Shard::WHOLE);
        let r = used.references.values().next().unwrap();
        assert!(r.converged);
        assert_eq!(r.spp, 15);
        assert_eq!(r.rel_mse, Some(rel_mse));
        assert!(
            !cache.exists(),
            "the cache was used beside a matching converged reference"
        );
        // More samples asked than stored, or other settings: the cache.
        for edit in ["spp = 16", "spp = 8\nmax_depth = 2"] {
            let other =
                Suite::parse("converged.toml", &text.replace("spp = 8", edit), &parts).unwrap();
            let fell_back = run_suite(ctx, &other, &dir.join("b"), &cache, Shard::WHOLE);
            assert!(
                !fell_back.references.values().next().unwrap().converged,
                "{edit}"
            );
            let _ = fs::remove_dir_all(dir.join("b"));
        }
        assert!(cache.exists());
    });
    let _ = fs::remove_dir_all(&dir);
}

/// A run of `irad bench references` that ends before its first chunk is saved (stopped, or a
/// chunk failing) leaves no folder behind: a folder without a record among those kept beside
/// a scene would be taken for a damaged reference by whatever walks them.
#[test]
fn a_converged_reference_stopped_before_its_first_chunk_leaves_no_folder() {
    use irad::bench::suite::converged::{self, ConvergedKey, ExtendOptions};
    use irad::methods::Renderers;
    use irad::scene::gpu::GpuScene;
    use std::sync::atomic::AtomicBool;

    let dir = temp_dir("converged-empty");
    copy_plane_scene(&dir.join("plane"));
    let text = &PLANE_SUITE.replace("NAME", "converged-empty");
    let suite = Suite::parse("converged-empty.toml", text, &dir).unwrap();
    let s = &suite.scenes[0];
    let key_dir = ConvergedKey::new(&s.scene, &s.reference).dir(&dir.join("plane"));
    common::with_gpu(|ctx| {
        let gpu = GpuScene::upload(ctx, &s.scene).unwrap();
        let stop = AtomicBool::new(true);
        let options = ExtendOptions {
            target_rel_mse: 1e-12,
            deadline: None,
            chunk_spp: 3,
            stop: Some(&stop),
        };
        let done = converged::extend(
            ctx,
            &Renderers::default(),
            &s.scene,
            &gpu,
            &s.reference,
            &options,
            |_| {},
        )
        .unwrap();
        assert_eq!(done.record.chunks, 0);
    });
    assert!(!key_dir.exists(), "{} left behind", key_dir.display());
    let _ = fs::remove_dir_all(&dir);
}

/// `irad bench references` holds the converged reference's folder while it writes: a second
/// writer is refused with the folder and the holder named, and a lock left by a process that
/// is gone is taken over with a note. A record whose samples per half disagree with its chunks
/// (a hand edit) is refused, naming the file and both values, when extending it and when a
/// suite would use it.
#[test]
fn converged_references_are_locked_and_their_records_checked() {
    use irad::bench::suite::converged::{self, ConvergedKey, ExtendOptions, Progress};
    use irad::methods::Renderers;
    use irad::scene::gpu::GpuScene;
    use std::sync::atomic::{AtomicBool, Ordering};

    let dir = temp_dir("converged-lock");
    copy_plane_scene(&dir.join("plane"));
    let text = &PLANE_SUITE.replace("NAME", "converged-lock");
    let suite = Suite::parse("converged-lock.toml", text, &dir).unwrap();
    let s = &suite.scenes[0];
    let key_dir = ConvergedKey::new(&s.scene, &s.reference).dir(&dir.join("plane"));
    fs::create_dir_all(&key_dir).unwrap();
    let held = irad::lock::HolderLock::acquire(&key_dir).unwrap().lock;
    let pid = format!("pid {}", std::process::id());
    // The shipped converged references (sessions of different chunk sizes among them) agree
    // with their chunks.
    let mut shipped = 0;
    for scene in fs::read_dir(scenes_dir().join("failure")).unwrap() {
        let Ok(entries) = fs::read_dir(scene.unwrap().path().join(converged::FOLDER)) else {
            continue;
        };
        for entry in entries {
            let path = entry.unwrap().path();
            converged::load(&path)
                .unwrap_or_else(|e| panic!("{e:#}"))
                .unwrap_or_else(|| panic!("{}: no record", path.display()));
            shipped += 1;
        }
    }
    assert!(shipped >= 3, "{shipped} shipped converged references");
    common::with_gpu(|ctx| {
        let renderers = Renderers::default();
        let gpu = GpuScene::upload(ctx, &s.scene).unwrap();
        let extend = |chunks: u32, notes: &mut Vec<String>| {
            let stop = AtomicBool::new(false);
            let options = ExtendOptions {
                target_rel_mse: 1e-12,
                deadline: None,
                chunk_spp: 3,
                stop: Some(&stop),
            };
            converged::extend(
                ctx,
                &renderers,
                &s.scene,
                &gpu,
                &s.reference,
                &options,
                |e| match e {
                    Progress::Saved { record, .. } if record.chunks >= chunks => {
                        stop.store(true, Ordering::SeqCst)
                    }
                    Progress::StaleLock { holder, .. } => notes.push(format!("stale {holder}")),
                    _ => {}
                },
            )
        };
        let mut notes = Vec::new();
        let e = format!("{:#}", extend(3, &mut notes).unwrap_err());
        assert!(
            e.contains(key_dir.to_str().unwrap()) && e.contains(&pid),
            "{e}"
        );
        assert!(!key_dir.join("reference.json").exists());
        drop(held);
        // A lock file whose process is gone (no flock held on it).
        fs::write(key_dir.join(irad::lock::LOCK_FILE), "pid 4000000 on gone\n").unwrap();
        let done = extend(3, &mut notes).unwrap();
        assert_eq!(notes, ["stale irad (pid 4000000 on gone)"]);
        assert!(!key_dir.join(irad::lock::LOCK_FILE).exists());
        assert_eq!(done.record.spp, [6, 3]);
        // The record edited by hand: its samples no longer those of its 3 chunks of 3.
        let record = key_dir.join("reference.json");
        let mut json: serde_json::Value =
            serde_json::from_str(&fs::read_to_string(&record).unwrap()).unwrap();
        json["spp"] = serde_json::json!([100000, 100000]);
        fs::write(&record, serde_json::to_string_pretty(&json).unwrap()).unwrap();
        let e = format!("{:#}", extend(4, &mut notes).unwrap_err());
        let named = |e: &str| {
            e.contains(record.to_str().unwrap())
                && e.contains("[100000, 100000]")
                && e.contains("[6, 3]")
        };
        assert!(named(&e), "{e}");
        let results = run_suite(
            ctx,
            &suite,
            &dir.join("out"),
            &dir.join("cache"),
            Shard::WHOLE,
        );
        assert!(
            !dir.join("cache").exists(),
            "the suite fell back to the cache"
        );
        for r in &results.runs {
            assert_eq!(r.status, Status::Error);
            assert!(named(&r.note), "{}", r.note);
        }
    });
    let _ = fs::remove_dir_all(&dir);
}

/// `irad bench references` prints the net relMSE and the target to three significant digits
/// however small they are (a target under 1e-4 is reached at figures that four decimals
/// print as 0.0000).
#[test]
fn reference_progress_shows_small_rel_mse() {
    use irad::bench::suite::converged::{self, ExtendOptions, Progress};
    use irad::methods::Renderers;
    use irad::scene::gpu::GpuScene;
    use std::sync::atomic::{AtomicBool, Ordering};

    let dir = temp_dir("converged-figures");
    copy_plane_scene(&dir.join("plane"));
    let text = PLANE_SUITE.replace("NAME", "converged-figures");
    fs::write(dir.join("suite.toml"), &text).unwrap();
    let suite = Suite::parse("suite.toml", &text, &dir).unwrap();
    let s = &suite.scenes[0];
    let done = std::cell::RefCell::new(None);
    common::with_gpu(|ctx| {
        let gpu = GpuScene::upload(ctx, &s.scene).unwrap();
        let stop = AtomicBool::new(false);
        let options = ExtendOptions {
            target_rel_mse: 1e-12,
            deadline: None,
            chunk_spp: 2,
            stop: Some(&stop),
        };
        let c = converged::extend(
            ctx,
            &Renderers::default(),
            &s.scene,
            &gpu,
            &s.reference,
            &options,
            |e| {
                if let Progress::Saved { record, .. } = e {
                    stop.store(record.chunks >= 2, Ordering::SeqCst);
                }
            },
        )
        .unwrap();
        *done.borrow_mut() = Some(c);
    });
    // Halves 0.3% apart, as after a long run: a net relMSE far under 1e-4.
    let mut c = done.into_inner().unwrap();
    c.halves[1].pixels = c.halves[0]
        .pixels
        .iter()
        .map(|p| p.map(|v| v * 1.003))
        .collect();
    let mut stacked = irad::image::Image::new(8, 16);
    stacked.pixels = c.halves.iter().flat_map(|h| h.pixels.clone()).collect();
    irad::image::exr::write(&c.halves_path(), &stacked).unwrap();
    let rel_mse = c.image().1;
    assert!(rel_mse > 0.0 && rel_mse < 1e-5, "{rel_mse}");
    c.record.rel_mse = Some(rel_mse);
    fs::write(
        c.dir.join("reference.json"),
        serde_json::to_string_pretty(&c.record).unwrap(),
    )
    .unwrap();
    // The target met already: nothing is rendered, and both figures are printed.
    let target = 2.0 * rel_mse;
    let o = irad(&[
        "bench",
        "references",
        dir.join("suite.toml").to_str().unwrap(),
        "--target",
        &format!("{target:e}"),
    ]);
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(
        o.status.success(),
        "{out}{}",
        String::from_utf8_lossy(&o.stderr)
    );
    // The printed net relMSE and target, each within 0.5% of its value.
    let figures: Vec<f64> = out
        .split(|c: char| c.is_whitespace() || "(),;".contains(c))
        .filter_map(|w| w.parse().ok())
        .collect();
    let near = |x: f64| figures.iter().any(|f| (f / x - 1.0).abs() < 5e-3);
    assert!(near(rel_mse) && near(target), "{out}");
    assert!(out.contains(" reached)"), "{out}");
    let _ = fs::remove_dir_all(&dir);
}

/// A suite refused its folder's results after an edit names the edit: the suite field with
/// its old and new values, or the scene whose file (or a file it references) changed. Results
/// written before irad recorded the suite's text still name the scene, and otherwise say the
/// suite file changed.
#[test]
fn a_refused_resume_names_the_edit() {
    let dir = temp_dir("resume-edit");
    copy_plane_scene(&dir.join("plane"));
    let text = PLANE_SUITE.replace("NAME", "edited");
    let (out, cache) = (dir.join("out"), dir.join("cache"));
    let parse = |text: &str| Suite::parse("edited.toml", text, &dir).unwrap();
    common::with_gpu(|ctx| {
        run_suite(ctx, &parse(&text), &out, &cache, Shard::WHOLE);
        let refused = |text: &str| {
            let suite = parse(text);
            let r = run_suite_events(ctx, &suite, &out, &cache, Shard::WHOLE, &mut Vec::new());
            format!("{:#}", r.unwrap_err())
        };
        // The suite's hash alone changed (results.json edited, or another irad's hashing):
        // no field or scene to name, and the message says so.
        let path = out.join("results.json");
        let written = fs::read_to_string(&path).unwrap();
        let mut json: serde_json::Value = serde_json::from_str(&written).unwrap();
        json["suite_hash"] = serde_json::json!("0123456789abcdef");
        fs::write(&path, serde_json::to_string_pretty(&json).unwrap()).unwrap();
        let e = refused(&text);
        assert!(
            e.contains("before an edit: the suite file edited.toml or a scene it names: its text differs in a way irad cannot name (suite hash 0123456789abcdef"),
            "{e}"
        );
        fs::write(&path, written).unwrap();
        let e = refused(&text.replace("repeats = 1", "repeats = 2"));
        assert!(e.contains("`repeats` was 1, now 2"), "{e}");
        let e = refused(&text.replace("spp = 8", "spp = 8\nmax_depth = 3"));
        assert!(e.contains("`reference.max_depth` was absent, now 3"), "{e}");
        let e = refused(&text.replace("budgets = [{ spp = 1 }]", "budgets = [{ spp = 2 }]"));
        assert!(e.contains("`method[0].budgets[0].spp` was 1, now 2"), "{e}");
        let e = refused(&text.replace("repeats = 1", "repeats = 1 # one"));
        assert!(e.contains("comments or layout"), "{e}");
        let scene = dir.join("plane").join("scene.toml");
        let mut edited = fs::read_to_string(&scene).unwrap();
        edited.push_str("\n# edited\n");
        fs::write(&scene, edited).unwrap();
        let e = refused(&text);
        assert!(
            e.contains("scene `plane` (plane/scene.toml)") && !e.contains("was"),
            "{e}"
        );
        // Results from before the suite's text and scenes were recorded.
        let path = out.join("results.json");
        let mut json: serde_json::Value =
            serde_json::from_str(&fs::read_to_string(&path).unwrap()).unwrap();
        let fields = json.as_object_mut().unwrap();
        fields.remove("suite_text");
        fields.remove("scene_files");
        fs::write(&path, serde_json::to_string_pretty(&json).unwrap()).unwrap();
        let e = refused(&text);
        assert!(e.contains("scene `plane` (plane/scene.toml)"), "{e}");
        let e = refused(&text.replace("repeats = 1", "repeats = 2"));
        assert!(e.contains("the suite file"), "{e}");
    });
    let _ = fs::remove_dir_all(&dir);
}

/// An animated scene in a suite with still budgets (a fixed count) is refused naming the
/// budget and the scene: its runs are timed per frame (`frame_ms`).
#[test]
fn an_animated_scene_in_a_suite_is_refused() {
    let text = TINY_SUITE.replace(
        "point-light-plane/scene.toml",
        "cornell-circling/scene.toml",
    );
    let e = Suite::parse("animated.toml", &text, &scenes_dir())
        .err()
        .unwrap()
        .to_string();
    assert!(
        e.contains("method[0].budgets[0].spp = 1")
            && e.contains("scene[1] (cornell-circling) is animated (24 frames)")
            && e.contains("frame_ms"),
        "{e}"
    );
}

/// Copies the animated Cornell box (cornell-circling, which reads ../cornell-box's mesh) under
/// `base` (scene folders of a test's own: converged references are written beside them).
fn copy_circling_scene(base: &Path) {
    for (folder, files) in [
        ("cornell-circling", &["scene.toml"][..]),
        ("cornell-box", &["cornell-box.obj", "cornell-box.mtl"][..]),
    ] {
        fs::create_dir_all(base.join(folder)).unwrap();
        for f in files {
            fs::copy(scenes_dir().join(folder).join(f), base.join(folder).join(f)).unwrap();
        }
    }
}

/// A suite of the copied animated Cornell box at 8x8, frames 0..3, and two frame budgets of
/// the path tracer; NAME is replaced by the suite's name.
const CIRCLING_SUITE: &str = r#"
name = "NAME"
warmup = 0
repeats = 1
flicker_frames = 0
[reference]
spp = 4
[[scene]]
path = "cornell-circling/scene.toml"
resolution = [8, 8]
frames = "0..3"
[[method]]
method = "reference"
label = "pt"
budgets = [{ frame_ms = 1 }, { frame_ms = 4 }]
"#;

/// The converged-reference folders beside the copied cornell-circling, by name.
fn frame_reference_dirs(base: &Path) -> Vec<String> {
    let Ok(entries) = fs::read_dir(base.join("cornell-circling").join("converged")) else {
        return vec![];
    };
    let mut names: Vec<String> = entries
        .map(|e| e.unwrap().file_name().into_string().unwrap())
        .collect();
    names.sort();
    names
}

/// Per-frame references (docs/DESIGN.md "Animation"): `irad bench references` renders one converged reference per animation
/// frame (the suite's `frames`), keyed by the scene's hash and the frame (the frame's scene
/// has the file's hash); a frame stopped after one chunk and resumed has the bits of one run
/// straight through; `--shard I/N` takes frames f with f mod N = I, and a bad I/N is refused;
/// the suite reads each frame's reference and names frames without one.
#[test]
fn per_frame_references_resume_shard_and_are_used_by_suites() {
    use irad::bench::suite::converged::{self, ConvergedKey, ExtendOptions, Progress};
    use irad::methods::Renderers;
    use std::sync::atomic::{AtomicBool, Ordering};

    let dir = temp_dir("frame-references");
    let text = CIRCLING_SUITE.replace("NAME", "frames");
    let (straight, parts) = (dir.join("straight"), dir.join("parts"));
    copy_circling_scene(&straight);
    copy_circling_scene(&parts);
    fs::write(parts.join("frames.toml"), &text).unwrap();
    let suite = Suite::parse("frames.toml", &text, &parts).unwrap();
    let s = &suite.scenes[0];
    assert_eq!(s.frames, Some(0..3));
    // at_frame keeps the file's hash, so the key carries the frame.
    let f1 = s.scene.at_frame(1).unwrap();
    assert_eq!(f1.content_hash, s.scene.content_hash);
    let key = |f: u32| ConvergedKey::of_frame(&s.scene, &s.reference, f);
    assert_ne!(key(0), key(1));
    assert_ne!(key(0).dir(&parts), key(1).dir(&parts));
    assert_eq!(ConvergedKey::of_frame(&f1, &s.reference, 1), key(1));
    common::with_gpu(|ctx| {
        let renderers = Renderers::default();
        let extend = |base: &Path, chunks: u32| {
            let suite = Suite::parse("frames.toml", &text, base).unwrap();
            let s = &suite.scenes[0];
            let stop = AtomicBool::new(false);
            let options = ExtendOptions {
                target_rel_mse: 1e-12,
                deadline: None,
                chunk_spp: 2,
                stop: Some(&stop),
            };
            converged::extend_frame(ctx, &renderers, &s.scene, 1, &s.reference, &options, |e| {
                if let Progress::Saved { record, .. } = e {
                    if record.chunks >= chunks {
                        stop.store(true, Ordering::SeqCst);
                    }
                }
            })
            .unwrap()
        };
        let whole = extend(&straight, 3);
        extend(&parts, 1);
        let resumed = extend(&parts, 3);
        assert_eq!(resumed.record.key.frame, Some(1));
        assert_eq!(resumed.record.spp, whole.record.spp);
        assert_eq!(resumed.record.sessions.len(), 2);
        let bits = |c: &converged::Converged| -> Vec<u32> {
            c.halves
                .iter()
                .flat_map(|h| h.pixels.iter().flatten().map(|v| v.to_bits()))
                .collect()
        };
        assert_eq!(bits(&resumed), bits(&whole), "resumed frame 1 differs");
    });
    // The CLI: shard 1/2 of frames 0..3 is frame 1 (already converged to 6 spp here; the
    // target is met at once), shard 0/2 frames 0 and 2; a bad shard is refused.
    let suite_file = parts.join("frames.toml");
    let suite_arg = suite_file.to_str().unwrap();
    let refs = |shard: &str| {
        irad(&[
            "bench",
            "references",
            suite_arg,
            "--chunk-spp",
            "4",
            "--target",
            "0.5",
            "--shard",
            shard,
        ])
    };
    for bad in ["2/2", "1/0", "x"] {
        let out = refs(bad);
        assert!(!out.status.success(), "--shard {bad} accepted");
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(err.contains("--shard") && err.contains("I/N"), "{err}");
    }
    let before = frame_reference_dirs(&parts);
    assert_eq!(before.len(), 1, "{before:?}");
    let out = refs("1/2");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(stdout.contains("cornell-circling frame 1:"), "{stdout}");
    assert!(
        !stdout.contains("frame 0:") && !stdout.contains("frame 2:"),
        "{stdout}"
    );
    assert_eq!(frame_reference_dirs(&parts), before);
    let out = refs("0/2");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        stdout.contains("frame 0:") && stdout.contains("frame 2:"),
        "{stdout}"
    );
    let dirs = frame_reference_dirs(&parts);
    assert_eq!(dirs.len(), 3, "{dirs:?}");
    for (f, d) in dirs.iter().enumerate() {
        assert!(d.starts_with(&format!("8x8-frame{f:04}-")), "{d}");
        let record = converged::load(&parts.join("cornell-circling/converged").join(d))
            .unwrap()
            .unwrap()
            .record;
        assert_eq!(record.key.frame, Some(f as u32));
        let session = &record.sessions[0];
        assert!(!session.device.is_empty() && !session.commit.is_empty());
        assert!(record.total_spp() > 0 && record.gpu_ms > 0.0);
    }
    // The suite uses each frame's; with frame 2's moved away, it says frame 2 has none and
    // uses the cache's for it.
    fs::rename(
        parts.join("cornell-circling/converged").join(&dirs[2]),
        dir.join("moved"),
    )
    .unwrap();
    let out_dir = dir.join("out");
    common::with_gpu(|ctx| {
        let results = run_suite(ctx, &suite, &out_dir, &dir.join("cache"), Shard::WHOLE);
        let r = &results.references["cornell-circling"];
        let converged: Vec<(u32, bool)> = r.frames.iter().map(|f| (f.frame, f.converged)).collect();
        assert_eq!(converged, [(0, true), (1, true), (2, false)]);
        assert!(!r.converged);
    });
    let report = fs::read_to_string(out_dir.join("report.md")).unwrap();
    assert!(
        report.contains("no converged reference for frames 2"),
        "{report}"
    );
    let _ = fs::remove_dir_all(&dir);
}

/// Frame-time budgets (docs/suites.md): a suite with frame-time budgets on an animated scene calibrates the count
/// per frame budget, renders the frames, and its results hold per-frame figures (one per frame
/// of its `frames`), the worst frame and the flicker; the CSV has them, the report a
/// frame-time table and a per-frame chart with a line per run and a point per frame, and the
/// relMSE-vs-time chart is per frame.
#[test]
fn a_frame_time_suite_records_per_frame_figures_and_flicker() {
    let dir = temp_dir("frame-time");
    copy_circling_scene(&dir);
    let text = CIRCLING_SUITE
        .replace("NAME", "frame-time")
        .replace("repeats = 1", "repeats = 2");
    let suite = Suite::parse("frame-time.toml", &text, &dir).unwrap();
    assert!(suite.runs.iter().all(|r| r.frame_ms.is_some()));
    let (out, cache) = (dir.join("out"), dir.join("cache"));
    common::with_gpu(|ctx| {
        let whole = run_suite(ctx, &suite, &out, &cache, Shard::WHOLE);
        // Interrupted after its first run: resumed with that run (its calibrated count and
        // per-frame figures) kept as it was, the second rendered again.
        let mut cut = whole.clone();
        cut.runs.truncate(1);
        cut.complete = false;
        cut.runs[0].wall_ms = Some(123456.0);
        fs::write(out.join("results.json"), cut.json()).unwrap();
        let mut events = Vec::new();
        let resumed =
            run_suite_events(ctx, &suite, &out, &cache, Shard::WHOLE, &mut events).unwrap();
        assert_eq!(events, ["resumed [0]"]);
        assert_eq!(
            resumed.runs[0].wall_ms,
            Some(123456.0),
            "run 0 rendered again"
        );
        assert_eq!(resumed.runs[0].sequence, whole.runs[0].sequence);
        assert!(resumed.complete);
    });
    let results = check_outputs(&out);
    assert!(results.complete);
    assert_eq!(results.runs.len(), 2);
    let frames = &results.references["cornell-circling"].frames;
    assert_eq!(
        frames.iter().map(|f| f.frame).collect::<Vec<_>>(),
        [0, 1, 2]
    );
    for r in &results.runs {
        assert_eq!(r.status, Status::Ok, "{}: {}", r.id, r.note);
        let seq = r.sequence.as_ref().unwrap();
        assert_eq!(seq.frames, [0, 3]);
        assert_eq!(seq.calibration_frame, 1);
        assert_eq!(seq.per_frame.len(), 3);
        assert_eq!(r.scored, 6);
        // The two seeds' sequences are different renders.
        assert!(
            r.rel_mse_min < r.rel_mse_max,
            "{:?}",
            (r.rel_mse_min, r.rel_mse_max)
        );
        // The image means against their frames' references, over frames and seeds.
        assert!(r.image_mean_offset.is_some_and(|o| o.abs() < 0.5), "{r:?}");
        assert!(r.image_mean_spread.is_some_and(|s| s > 0.0), "{r:?}");
        assert!(r.calibrated_count.is_some() && !r.calibration.is_empty());
        let rel: Vec<f64> = seq.per_frame.iter().map(|p| p.metrics.rel_mse).collect();
        assert!(rel.iter().all(|e| e.is_finite() && *e > 0.0), "{rel:?}");
        // The run's relMSE is the mean over frames (each the mean over seeds).
        let mean = rel.iter().sum::<f64>() / 3.0;
        assert!((r.metrics.unwrap().rel_mse - mean).abs() < 1e-9 * mean);
        let worst = seq
            .per_frame
            .iter()
            .max_by(|a, b| a.metrics.rel_mse.total_cmp(&b.metrics.rel_mse))
            .unwrap();
        assert_eq!(seq.worst_frame, worst.frame);
        assert_eq!(seq.worst_rel_mse, Some(worst.metrics.rel_mse));
        assert!(seq.flicker.is_some_and(|f| f.is_finite() && f > 0.0));
        // HDR-FLIP per frame, and the run's the mean over frames.
        assert!(seq.per_frame.iter().all(|p| p.metrics.flip.is_some()));
        let flip = seq
            .per_frame
            .iter()
            .map(|p| p.metrics.flip.unwrap())
            .sum::<f64>()
            / 3.0;
        assert!(
            (r.metrics.unwrap().flip.unwrap() - flip).abs() < 1e-9,
            "{flip}"
        );
        assert!(seq.per_frame.iter().all(|p| p.gpu_ms > 0.0));
        assert!(r.gpu_ms.is_some_and(|t| t > 0.0));
    }
    let rows = csv_rows(&out.join("results.csv"));
    for (row, r) in rows.iter().zip(&results.runs) {
        assert_eq!(row["frames"], "0..3");
        assert_eq!(row["frame_ms"], r.frame_ms.unwrap().to_string());
        let seq = r.sequence.as_ref().unwrap();
        assert_eq!(row["worst_frame"], seq.worst_frame.to_string());
        assert_eq!(row["sequence_flicker"], seq.flicker.unwrap().to_string());
        // The path tracer keeps nothing across frames: no lead-in.
        assert_eq!(row["lead_in"], "0");
    }
    let svg =
        fs::read_to_string(out.join(suite::output::frames_chart_path("cornell-circling"))).unwrap();
    let points = chart::read_frames_svg(&svg);
    assert_eq!(points.len(), 6, "{points:?}");
    for r in &results.runs {
        let name = format!("{} {}", r.label, r.budget);
        for p in &r.sequence.as_ref().unwrap().per_frame {
            assert!(
                points.contains(&(name.clone(), p.frame, p.metrics.rel_mse)),
                "{name} frame {}",
                p.frame
            );
        }
    }
    let time_chart =
        fs::read_to_string(out.join(suite::output::chart_path("cornell-circling"))).unwrap();
    assert!(time_chart.contains("GPU time per frame"));
    let report = fs::read_to_string(out.join("report.md")).unwrap();
    for needle in [
        "charts/cornell-circling-frames.svg",
        "| worst frame | worst relMSE | flicker | FLIP |",
        "Every frame's is a converged reference",
        "No frame has a converged reference",
    ] {
        assert_eq!(
            report.contains(needle),
            needle != "Every frame's is a converged reference",
            "{needle}: {report}"
        );
    }
    let _ = fs::remove_dir_all(&dir);
}

/// Animated scenes take frame-time budgets only, and frame-time budgets animated scenes only:
/// each wrong combination is refused at load, naming the field and the scene.
#[test]
fn animated_scenes_and_frame_budgets_refuse_bad_combinations_naming_the_field() {
    let dir = temp_dir("frame-time-refusals");
    copy_circling_scene(&dir);
    copy_plane_scene(&dir.join("plane"));
    let base = CIRCLING_SUITE.replace("NAME", "refusals");
    let still = PLANE_SUITE.replace("NAME", "refusals");
    let cases: Vec<(String, &str, &str)> = vec![
        (
            base.replace("{ frame_ms = 1 }", "{ time_ms = 1 }"),
            "method[0].budgets[0].time_ms = 1",
            "animated",
        ),
        (
            base.replace("{ frame_ms = 1 }", "{ spp = 2 }"),
            "method[0].budgets[0].spp = 2",
            "animated",
        ),
        (
            base.replace("{ frame_ms = 1 }", "{}"),
            "method[0].budgets[0] = { defaults }",
            "frame_ms",
        ),
        (
            base.replace("label = \"pt\"", "label = \"pt\"\nparams = { spp = 2 }"),
            "method[0].params.spp = 2",
            "calibrates spp itself",
        ),
        (
            base.replace("{ frame_ms = 1 }", "{ frame_ms = 1, time_ms = 2 }"),
            "method[0].budgets[0].frame_ms = 1",
            "not both",
        ),
        (
            base.replace("{ frame_ms = 1 }", "{ frame_ms = -1 }"),
            "method[0].budgets[0].frame_ms = -1",
            "GPU milliseconds",
        ),
        (
            base.replace("flicker_frames = 0", "flicker_frames = 0\nlead_in = -1"),
            "lead_in = -1",
            "integer >= 0",
        ),
        (
            base.replace("\"0..3\"", "\"2..2\""),
            "scene[0].frames = \"2..2\"",
            "24 frames",
        ),
        (
            base.replace("\"0..3\"", "\"0..25\""),
            "scene[0].frames = \"0..25\"",
            "24 frames",
        ),
        (
            still.replace("{ spp = 1 }", "{ frame_ms = 5 }"),
            "method[0].budgets[0].frame_ms = 5",
            "is not animated",
        ),
        (
            still.replace(
                "path = \"plane/scene.toml\"",
                "path = \"plane/scene.toml\"\nframes = \"0..2\"",
            ),
            "scene[0].frames = \"0..2\"",
            "not animated",
        ),
    ];
    for (text, field, problem) in cases {
        let e = Suite::parse("refusals.toml", &text, &dir)
            .unwrap_err()
            .to_string();
        assert!(e.contains(field) && e.contains(problem), "{field}: {e}");
    }
    // A mixed suite is fine where each method is limited to its kind of scene.
    let mixed = format!(
        "{base}\n[[scene]]\npath = \"plane/scene.toml\"\nresolution = [8, 8]\n[[method]]\nmethod = \"reference\"\nlabel = \"still\"\nscenes = [\"plane\"]\nbudgets = [{{ spp = 1 }}]\n"
    )
    .replace("label = \"pt\"", "label = \"pt\"\nscenes = [\"cornell-circling\"]");
    let suite = Suite::parse("refusals.toml", &mixed, &dir).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(suite.runs.len(), 3);
    let _ = fs::remove_dir_all(&dir);
}
