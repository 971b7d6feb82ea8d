//! The suite's output folder: results.json, results.csv, `charts/<scene>.svg` (and, for an
//! animated scene, `charts/<scene>-frames.svg`: relMSE per frame), report.md and
//! images/ (thumbnails and error maps, written by the runner), and its lock while a suite or a
//! merge writes it. Every file is written under a temporary name and renamed, so a reader (or
//! a Ctrl-C) never sees half a file.

use std::fs;
use std::path::Path;

use anyhow::{Context as _, Result};

use crate::bench::chart::{Chart, FrameChart, FrameSeries, Point, Series};
use crate::lock::HolderLock;

use super::file::file_safe;
use super::results::{Status, SuiteResults};
use super::{report, scale};

/// Creates `out` and takes its lock (`crate::lock::HolderLock`), held until the guard drops:
/// a second suite or merge writing the folder is refused, naming the holder. A lock left by a
/// process that is gone is taken over and `stale` told its holder.
pub fn lock(out: &Path, stale: &mut dyn FnMut(String)) -> Result<HolderLock> {
    fs::create_dir_all(out)
        .with_context(|| format!("creating the output folder {}", out.display()))?;
    let acquired = HolderLock::acquire(out)?;
    if let Some(holder) = acquired.stale {
        stale(holder);
    }
    Ok(acquired.lock)
}

/// Creates images/ and charts/ in `out`. Unless `resume`, what an earlier run of the suite
/// wrote there (images/, charts/, results and report; only when its results.json says it is a
/// suite's folder) is removed first, so no stale chart or image survives; anything else in the
/// folder is left alone.
pub fn prepare(out: &Path, resume: bool) -> Result<()> {
    if !resume && out.join("results.json").is_file() {
        for dir in ["images", "charts"] {
            let d = out.join(dir);
            if d.exists() {
                fs::remove_dir_all(&d).with_context(|| format!("removing {}", d.display()))?;
            }
        }
        for f in ["results.json", "results.csv", "report.md"] {
            let _ = fs::remove_file(out.join(f));
        }
    }
    for dir in ["images", "charts"] {
        let d = out.join(dir);
        fs::create_dir_all(&d).with_context(|| format!("creating {}", d.display()))?;
    }
    Ok(())
}

/// The chart file of `scene`, relative to the output folder.
pub fn chart_path(scene: &str) -> String {
    format!("charts/{}.svg", file_safe(scene))
}

/// The per-frame chart of an animated scene, relative to the output folder.
pub fn frames_chart_path(scene: &str) -> String {
    format!("charts/{}-frames.svg", file_safe(scene))
}

/// Whether `scene` has frame-time runs (an animated scene).
pub fn animated(results: &SuiteResults, scene: &str) -> bool {
    results
        .runs
        .iter()
        .any(|r| r.scene == scene && r.frame_ms.is_some())
}

/// Per-frame relMSE over frame number for an animated scene: a line per ok frame-time run
/// (method label and budget, and device when the results mix devices).
pub fn frames_chart(results: &SuiteResults, scene: &str) -> FrameChart {
    let mixed = results
        .runs
        .iter()
        .any(|r| r.device != results.runs[0].device);
    let series = results
        .runs
        .iter()
        .filter(|r| r.scene == scene && r.status == Status::Ok)
        .filter_map(|r| {
            let seq = r.sequence.as_ref()?;
            let name = match mixed {
                true => format!("{} {} ({})", r.label, r.budget, r.device),
                false => format!("{} {}", r.label, r.budget),
            };
            Some(FrameSeries {
                name,
                points: seq
                    .per_frame
                    .iter()
                    .map(|p| (p.frame, p.metrics.rel_mse))
                    .collect(),
            })
        })
        .collect();
    FrameChart {
        title: format!("{scene}: relMSE per frame ({})", results.device),
        y_label: "relMSE against the frame's reference (mean over seeds)".into(),
        series,
    }
}

/// relMSE against GPU time for one scene: a series per method label (and device, when the
/// results mix devices), a point per ok run.
pub fn chart(results: &SuiteResults, scene: &str) -> Chart {
    let mut series: Vec<Series> = Vec::new();
    let mixed = results
        .runs
        .iter()
        .any(|r| r.device != results.runs[0].device);
    for r in results
        .runs
        .iter()
        .filter(|r| r.scene == scene && r.status == Status::Ok)
    {
        let name = if mixed {
            format!("{} ({})", r.label, r.device)
        } else {
            r.label.clone()
        };
        let point = Point {
            x: r.gpu_ms.unwrap_or(f64::NAN),
            y: r.metrics.map(|m| m.rel_mse).unwrap_or(f64::NAN),
            y_range: r.rel_mse_min.zip(r.rel_mse_max),
            label: r.budget.clone(),
            run_id: r.id.clone(),
        };
        match series.iter_mut().find(|s| s.name == name) {
            Some(s) => s.points.push(point),
            None => series.push(Series {
                name,
                points: vec![point],
            }),
        }
    }
    if animated(results, scene) {
        return Chart {
            title: format!(
                "{scene}: mean per-frame relMSE against frame time ({})",
                results.device
            ),
            x_label: "GPU time per frame (ms, median over frames and seeds)".into(),
            y_label: "relMSE, mean over frames and seeds".into(),
            series,
            notes: Vec::new(),
            floor: None,
        };
    }
    Chart {
        title: format!("{scene}: relMSE against GPU time ({})", results.device),
        x_label: "GPU time per image (ms, median of repeats)".into(),
        y_label: "relMSE".into(),
        series,
        notes: Vec::new(),
        floor: results.references.get(scene).and_then(|r| r.rel_mse),
    }
}

/// Held while the outputs are written, so an exit never leaves them disagreeing.
static WRITING: std::sync::Mutex<()> = std::sync::Mutex::new(());

/// Exits the process with `code` once no output is being written (a second Ctrl-C: the files
/// on disk then always agree with each other).
pub fn exit_after_writing(code: i32) -> ! {
    let _writing = WRITING.lock().unwrap_or_else(|e| e.into_inner());
    std::process::exit(code)
}

/// Writes results.json, results.csv, one chart per scene, a generated family's charts against
/// its light count (scale.rs) and report.md.
pub fn write(out: &Path, results: &SuiteResults) -> Result<()> {
    let _writing = WRITING.lock().unwrap_or_else(|e| e.into_inner());
    atomic_write(&out.join("results.json"), &results.json())?;
    atomic_write(&out.join("results.csv"), &results.csv())?;
    for scene in results.scenes() {
        atomic_write(
            &out.join(chart_path(&scene)),
            &chart(results, &scene).to_svg(),
        )?;
        if animated(results, &scene) {
            atomic_write(
                &out.join(frames_chart_path(&scene)),
                &frames_chart(results, &scene).to_svg(),
            )?;
        }
    }
    for family in scale::families(results) {
        for (path, chart) in scale::charts(results, &family) {
            let path = out.join(path);
            if let Some(dir) = path.parent() {
                fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
            }
            atomic_write(&path, &chart.to_svg())?;
        }
    }
    atomic_write(&out.join("report.md"), &report::markdown(results))?;
    // The page reads every run's image, so it is written once the suite is complete (each
    // write of an incomplete suite would read them all again).
    if results.complete {
        // The page is a view of what is written above: a failure to make it is said, not
        // fatal to the suite (or to a merge) whose results are on disk.
        match super::html::page(out, results) {
            Ok(page) => atomic_write(&out.join("report.html"), &page)?,
            Err(e) => log::warn!("report.html not written: {e:#}"),
        }
    }
    Ok(())
}

fn atomic_write(path: &Path, text: &str) -> Result<()> {
    let mut tmp = path.as_os_str().to_owned();
    tmp.push(format!(".{}.tmp", std::process::id()));
    let tmp = std::path::PathBuf::from(tmp);
    fs::write(&tmp, text).with_context(|| format!("writing {}", tmp.display()))?;
    fs::rename(&tmp, path)
        .with_context(|| format!("renaming {} to {}", tmp.display(), path.display()))
}
