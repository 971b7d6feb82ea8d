//! report.md: what ran on what, then per scene its expected failure (the scene's `[failure]`
//! table), its chart, a table of every run with the Pareto-optimal ones marked, and the
//! thumbnails beside their error maps.

use std::fmt::Write as _;

use crate::image::preview::{ERROR_MAP_MAX, ERROR_MAP_MIN};

use super::output::{animated, chart_path, frames_chart_path};
use super::results::{
    plausible, RunRecord, Status, SuiteResults, STAR_MAX_BIAS, STAR_MAX_OUTLIERS,
};

/// The mark of a Pareto-optimal run in the report's tables.
pub const PARETO_MARK: &str = "★";

pub fn markdown(results: &SuiteResults) -> String {
    let mut md = String::new();
    let _ = writeln!(md, "# Benchmark suite `{}`\n", results.suite);
    if !results.description.is_empty() {
        let _ = writeln!(md, "{}\n", results.description.trim());
    }
    let state = if results.complete {
        "complete".to_string()
    } else {
        "**incomplete** (still running, or interrupted)".to_string()
    };
    let shard = match results.shard {
        Some(s) => format!("shard {s} of the suite's {} runs", results.runs_in_suite),
        None => format!("all {} runs of the suite", results.runs_in_suite),
    };
    let _ = writeln!(
        md,
        "- Suite file `{}` (hash {}), {shard}: {} of {} planned runs recorded, {state}.",
        results.suite_file,
        results.suite_hash,
        results.runs.len(),
        results.runs_planned
    );
    let _ = writeln!(
        md,
        "- Device: {} (driver {}), irad {}.",
        results.device, results.driver, results.irad_version
    );
    let _ = writeln!(
        md,
        "- GPU and wall times are medians over each run's repeats (successive seeds) after its \
         warm-up renders; each error figure is the mean over the run's images (successive \
         seeds) of that image's figure against the scene's reference (docs/DESIGN.md \"Error \
         metrics\"); flicker is the per-pixel temporal variance over the flicker frames \
         relative to the reference, averaged, square-rooted. {PARETO_MARK} marks the runs no other \
         run of the scene beats in both GPU time and relMSE (on the same device); a run with \
         NaN/Inf, a bias over {:.0}% or outliers over {:.0}% of its pixels (a plainly wrong \
         image: black, or fireflies) is never marked.{LIMITED_MARK} marks a relMSE within {LIMITED_FACTOR}x of the \
         reference's own (estimated from its two halves): there the reference's noise, not the \
         run, sets the figure; render the reference with more samples.",
        100.0 * STAR_MAX_BIAS,
        100.0 * STAR_MAX_OUTLIERS
    );
    let _ = writeln!(
        md,
        "- Error maps: per-pixel relMSE, log scale from {ERROR_MAP_MIN:e} (black) through red \
         and yellow to {ERROR_MAP_MAX} (white); magenta marks NaN/Inf.\n"
    );
    md += "- relMSE is at most 1 where an image is too dark (x = 0 gives r^2 / (r^2 + 0.01)) but \
           unbounded for fireflies: a method that misses light altogether can chart below one \
           that finds it noisily. Read relMSE with the bias and outliers columns.\n\n";
    md += "Data: [results.csv](results.csv), [results.json](results.json).\n\n";
    md += &super::scale::markdown(results);

    for scene in results.scenes() {
        let runs: Vec<&RunRecord> = results.runs.iter().filter(|r| r.scene == scene).collect();
        let _ = writeln!(md, "## {scene}\n");
        md += &summary(&runs);
        let reference = results.references.get(&scene);
        if let Some(r) = reference {
            if !r.expected_to_fail.is_empty() {
                let _ = writeln!(
                    md,
                    "Stability scene: expected to fail here: **{}**. {} ({})\n",
                    r.expected_to_fail.join(", "),
                    r.why.trim(),
                    r.source
                );
            }
            let noise = match r.rel_mse {
                Some(e) => format!(" Its own relMSE, estimated from its two halves: {e:.3e}."),
                None => String::new(),
            };
            if r.frames.is_empty() {
                let _ = writeln!(
                    md,
                    "Reference: {} samples per pixel (seeds {} and {}, half each), cached at `{}`.{noise}\n",
                    r.spp,
                    r.seed,
                    r.seed.wrapping_add(1),
                    r.cache
                );
            } else {
                md += &frame_references(r);
            }
        }
        let _ = writeln!(md, "![relMSE against GPU time]({})\n", chart_path(&scene));
        if animated(results, &scene) {
            let _ = writeln!(md, "![relMSE per frame]({})\n", frames_chart_path(&scene));
            md += &sequence_table(&runs);
        }
        md += "| | method | budget | GPU ms | wall ms | relMSE | RMSE | Lab error | bias | outliers | NaN/Inf | flicker | status |\n";
        md += "|---|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---|\n";
        for r in &runs {
            let m = r.metrics;
            let mark = if r.pareto { PARETO_MARK } else { "" };
            let status = match r.status {
                Status::Ok if r.expected_failure => "ok (expected to fail)".to_string(),
                Status::Ok => "ok".to_string(),
                s => format!("{}: {}", s.as_str(), r.note),
            };
            let _ = writeln!(
                md,
                "| {mark} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} |",
                r.label,
                r.budget,
                fixed(r.gpu_ms, 2) + missed_mark(r),
                fixed(r.wall_ms, 1),
                sci(m.map(|m| m.rel_mse))
                    + if limited_by_reference(r) {
                        LIMITED_MARK
                    } else {
                        ""
                    },
                sci(m.map(|m| m.rmse)),
                fixed(m.map(|m| m.lab_error), 2),
                percent(m.map(|m| m.bias)),
                percent(m.map(|m| m.outliers)),
                m.map(|m| m.nan_inf.to_string())
                    .unwrap_or_else(|| "-".into()),
                fixed(r.flicker, 3),
                escape(&status)
            );
        }
        md += "\n";
        md += &missed_footnotes(&runs);
        md += &equal_time_table(&runs);
        md += &pass_times(&runs);
        md += &method_figures(&runs);
        md += "| run | image | error map |\n|---|---|---|\n";
        if let Some(r) = reference {
            let _ = writeln!(
                md,
                "| reference ({} spp) | ![reference]({}) | |",
                r.spp, r.image
            );
        }
        for r in &runs {
            if let (Some(image), Some(error)) = (&r.image, &r.error_map) {
                let _ = writeln!(
                    md,
                    "| {} {} | ![{}]({image}) | ![error]({error}) |",
                    r.label, r.budget, r.label
                );
            }
        }
        md += "\n";
    }
    md
}

/// An animated scene's references, one per frame: which are converged (stored beside the
/// scene by `irad bench references`) and which the cache's, their samples and own relMSE.
fn frame_references(r: &super::results::ReferenceSummary) -> String {
    let list = |converged: bool| -> Vec<String> {
        r.frames
            .iter()
            .filter(|f| f.converged == converged)
            .map(|f| f.frame.to_string())
            .collect()
    };
    let (stored, cached) = (list(true), list(false));
    let spp_lo = r.frames.iter().map(|f| f.spp).min().unwrap_or(0);
    let spp_hi = r.frames.iter().map(|f| f.spp).max().unwrap_or(0);
    let worst = r
        .frames
        .iter()
        .filter_map(|f| f.rel_mse)
        .fold(None, |m: Option<f64>, e| Some(m.map_or(e, |m| m.max(e))));
    let mut md = format!(
        "References: one per animation frame ({} frames, {}..={}), {} to {} samples per pixel",
        r.frames.len(),
        r.frames.first().map_or(0, |f| f.frame),
        r.frames.last().map_or(0, |f| f.frame),
        spp_lo,
        spp_hi
    );
    if let Some(e) = worst {
        let _ = write!(md, ", own relMSE (from their halves) at most {e:.3e}");
    }
    md += ". ";
    if cached.is_empty() {
        md += "Every frame's is a converged reference stored beside the scene (`irad bench references`).";
    } else if stored.is_empty() {
        md += "No frame has a converged reference stored beside the scene: each is the cache's \
               (rendered now when missing); `irad bench references <suite>` renders converged ones.";
    } else {
        let _ = write!(
            md,
            "Converged (stored beside the scene) for frames {}; no converged reference for frames \
             {}, which use the cache's (rendered now when missing; `irad bench references \
             <suite>` renders them).",
            stored.join(", "),
            cached.join(", ")
        );
    }
    md += " The thumbnail below is the calibration frame's.\n\n";
    md
}

/// The frame-time runs of an animated scene: frame time, mean and worst per-frame relMSE,
/// flicker.
fn sequence_table(runs: &[&RunRecord]) -> String {
    let with: Vec<&&RunRecord> = runs.iter().filter(|r| r.frame_ms.is_some()).collect();
    if with.is_empty() {
        return String::new();
    }
    let mut md = String::from(
        "Frame-time runs: each method's count calibrated to the frame budget on the calibration \
         frame, then every frame rendered independently with its own seed (the sequence once per \
         seed); frame ms: the median frame's GPU time; relMSE: the mean over frames and seeds of \
         each frame against its own reference; worst frame: the frame with the highest relMSE \
         (mean over seeds); flicker: the temporal change of the error from frame to frame \
         relative to the reference's own change (docs/DESIGN.md \"Error metrics\"), mean over \
         seeds; FLIP: HDR-FLIP's mean over frames and seeds.\n\n",
    );
    md += "| | method | frame budget ms | count | frame ms | relMSE | worst frame | worst relMSE | flicker | FLIP | bias | outliers | status |\n";
    md += "|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---|\n";
    for r in with {
        let m = r.metrics;
        let seq = r.sequence.as_ref();
        let status = match r.status {
            Status::Ok => "ok".to_string(),
            s => format!("{}: {}", s.as_str(), r.note),
        };
        let _ = writeln!(
            md,
            "| {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} |",
            if r.pareto { PARETO_MARK } else { "" },
            r.label,
            fixed(r.frame_ms, 2),
            r.calibrated_count
                .map(|c| c.to_string())
                .unwrap_or_else(|| "-".into()),
            fixed(r.gpu_ms, 2) + missed_mark(r),
            sci(m.map(|m| m.rel_mse))
                + if limited_by_reference(r) {
                    LIMITED_MARK
                } else {
                    ""
                },
            seq.map(|s| s.worst_frame.to_string())
                .unwrap_or_else(|| "-".into()),
            sci(seq.and_then(|s| s.worst_rel_mse)),
            fixed(seq.and_then(|s| s.flicker), 3),
            fixed(m.and_then(|m| m.flip), 3),
            percent(m.map(|m| m.bias)),
            percent(m.map(|m| m.outliers)),
            escape(&status)
        );
    }
    md += "\n";
    md
}

/// The mark of a scene's home method (the suite's `home`) in the equal-time table.
pub const HOME_MARK: &str = "⌂";

/// Per time budget of the scene, every run at that budget: its calibrated count, GPU time,
/// error, and its speed against each reference (path tracer) label at the same budget:
/// relMSE x GPU time of the path tracer over the run's (docs/DESIGN.md "Speed at equal error"),
/// so over 1 the run reaches lower error in the same time. Empty without time budgets.
fn equal_time_table(runs: &[&RunRecord]) -> String {
    // A frame-time budget (an animated scene's) is a time budget per frame.
    let budgets = time_budgets(runs);
    if budgets.is_empty() {
        return String::new();
    }
    // relMSE x GPU time, from the relMSE with the reference's own noise taken out.
    let cost = |r: &RunRecord| -> Option<f64> {
        let e = net_rel_mse(r)? * r.gpu_ms?;
        (r.status == Status::Ok && e.is_finite() && e > 0.0).then_some(e)
    };
    let mut md = String::new();
    for budget in budgets {
        let at: Vec<&RunRecord> = runs
            .iter()
            .copied()
            .filter(|r| r.time_ms.or(r.frame_ms) == Some(budget))
            .collect();
        let references: Vec<&RunRecord> = at
            .iter()
            .copied()
            .filter(|r| r.method == "reference")
            .collect();
        let _ = writeln!(
            md,
            "Equal time, {budget} GPU ms{} ({HOME_MARK}: the scene's home method; image mean: the \
             mean over the run's images (successive seeds) of the image mean against the \
             reference's; spread: the standard deviation of those images' means, how far one \
             render's brightness moves from the next's; net relMSE: relMSE less the reference's own, estimated from its two \
             halves, so an estimate of the error against the converged image (- where the \
             reference's noise swamps it); speed: the path tracer's net relMSE x GPU time over \
             the run's, both from this device):\n",
            if at.iter().any(|r| r.frame_ms.is_some()) {
                " per frame (figures: means over the frames and seeds; the reference's own relMSE: the mean of the frames')"
            } else {
                ""
            }
        );
        md +=
            "| | method | count | GPU ms | relMSE | net relMSE | image mean | spread | outliers |";
        for r in &references {
            let _ = write!(md, " speed vs {} |", r.label);
        }
        md += "\n|---|---|---:|---:|---:|---:|---:|---:|---:|";
        md += &"---:|".repeat(references.len());
        md += "\n";
        for r in &at {
            let m = r.metrics;
            let _ = write!(
                md,
                "| {} | {} | {} | {} | {} | {} | {} | {} | {} |",
                if r.home { HOME_MARK } else { "" },
                r.label,
                r.calibrated_count
                    .map(|c| c.to_string())
                    .unwrap_or_else(|| "-".into()),
                fixed(r.gpu_ms, 1) + missed_mark(r),
                sci(m.map(|m| m.rel_mse))
                    + if limited_by_reference(r) {
                        LIMITED_MARK
                    } else {
                        ""
                    },
                sci(net_rel_mse(r).filter(|e| *e > 0.0)),
                signed_percent(r.image_mean_offset),
                percent(r.image_mean_spread),
                percent(m.map(|m| m.outliers)),
            );
            for reference in &references {
                let speed = match (cost(reference), cost(r)) {
                    (Some(a), Some(b)) => format!("{:.2}x", a / b),
                    _ => "-".into(),
                };
                let _ = write!(md, " {speed} |");
            }
            md += "\n";
        }
        md += "\n";
    }
    md
}

/// The runs' time budgets (a frame-time budget is a time budget per frame), ascending, each once.
fn time_budgets(runs: &[&RunRecord]) -> Vec<f64> {
    let mut budgets: Vec<f64> = runs
        .iter()
        .filter_map(|r| r.time_ms.or(r.frame_ms))
        .collect();
    budgets.sort_by(f64::total_cmp);
    budgets.dedup();
    budgets
}

/// The scene's one-line verdict: at each time budget, the run with the lowest net relMSE x GPU
/// time among those plausibly right (the star's thresholds) and how far ahead of the next
/// method it is; without time budgets, the starred runs.
fn summary(runs: &[&RunRecord]) -> String {
    // Net relMSE where the reference's noise leaves one, else the relMSE itself (a run within
    // the reference's noise is among the best, not out); GPU time, else wall time.
    let cost = |r: &RunRecord| -> Option<f64> {
        let gross = r.metrics?.rel_mse;
        let net = net_rel_mse(r).filter(|e| *e > 0.0).unwrap_or(gross);
        let e = net * r.gpu_ms.or(r.wall_ms)?;
        (plausible(r) && e.is_finite() && e > 0.0).then_some(e)
    };
    let budgets = time_budgets(runs);
    let mut parts = Vec::new();
    for budget in &budgets {
        let mut ranked: Vec<(f64, &RunRecord)> = runs
            .iter()
            .copied()
            .filter(|r| r.time_ms.or(r.frame_ms) == Some(*budget))
            .filter_map(|r| Some((cost(r)?, r)))
            .collect();
        ranked.sort_by(|a, b| a.0.total_cmp(&b.0));
        let per = if runs.iter().any(|r| r.frame_ms == Some(*budget)) {
            " a frame"
        } else {
            ""
        };
        let ran = runs.iter().any(|r| {
            r.time_ms.or(r.frame_ms) == Some(*budget)
                && r.status == Status::Ok
                && r.metrics.is_some()
        });
        parts.push(match ranked.as_slice() {
            [] if !ran => format!("at {budget} ms{per} no run was scored"),
            [] => format!("at {budget} ms{per} no run is plausibly right"),
            [(_, only)] => format!(
                "at {budget} ms{per} {} (the only plausible run)",
                only.label
            ),
            [(best, winner), rest @ ..] => {
                match rest.iter().find(|(_, r)| r.label != winner.label) {
                    Some((next, runner)) => format!(
                        "at {budget} ms{per} {} wins, {:.2}x ahead of {}",
                        winner.label,
                        next / best,
                        runner.label
                    ),
                    None => format!("at {budget} ms{per} {} wins", winner.label),
                }
            }
        });
    }
    if budgets.is_empty() {
        let starred: Vec<String> = runs
            .iter()
            .filter(|r| r.pareto)
            .map(|r| format!("{} {}", r.label, r.budget))
            .collect();
        parts.push(match starred.is_empty() {
            true => "no run is plausibly right (none starred)".into(),
            false => format!(
                "the best trade-offs of time and error: {}",
                starred.join("; ")
            ),
        });
    }
    format!(
        "**Summary** (net relMSE x GPU time among the runs within the star's thresholds): {}.\n\n",
        parts.join("; ")
    )
}

/// The methods' own figures (`stats`, averaged over each run's images), grouped by method and
/// named for people (`stat_name`), the record's key after each.
fn method_figures(runs: &[&RunRecord]) -> String {
    let mut methods: Vec<&str> = runs
        .iter()
        .filter(|r| !r.stats.is_empty())
        .map(|r| r.method.as_str())
        .collect();
    methods.dedup();
    methods.sort();
    methods.dedup();
    if methods.is_empty() {
        return String::new();
    }
    let mut md = String::from("Method figures (averaged over each run's images):\n\n");
    for method in methods {
        let _ = writeln!(md, "- **{method}**");
        for r in runs
            .iter()
            .filter(|r| r.method == method && !r.stats.is_empty())
        {
            let figures: Vec<String> = r
                .stats
                .iter()
                .map(|(k, v)| format!("{} {} (`{k}`)", stat_name(k), significant(*v)))
                .collect();
            let _ = writeln!(md, "  - {} {}: {}", r.label, r.budget, figures.join("; "));
        }
    }
    md + "\n"
}

/// A method's figure as people say it; the key itself where none is known.
pub fn stat_name(key: &str) -> &str {
    match key {
        "kept_standard_fraction" => "share of standard VPLs kept",
        "kept_reverse_fraction" => "share of reverse VPLs kept",
        "final_standard_weight" => "final weight of the standard side",
        "light_samples_per_pixel" => "light samples per pixel and frame",
        "effective_light_fraction" => "share of light samples above the surface",
        "alpha_samples" => "samples that estimated alpha",
        "mean_alpha" => "mean alpha (light sampling's share)",
        "iterations_per_chunk" => "iterations per dispatch",
        "light_vertices_per_iteration" => "light vertices per iteration",
        "bundle_env_offset" => "offset of the bundles' environment directions",
        "two_bounce_clamp" => "two-bounce clamp",
        "rays_per_iteration_max" => "most rays in one iteration",
        "reuse_kept_paths" => "light paths kept from earlier frames",
        "luminaire_samples_per_pixel" => "luminaire samples per lit pixel and frame",
        "pixels_with_luminaire_samples" => "pixels with luminaire samples",
        "most_luminaire_samples_per_pixel" => "most luminaire samples in one pixel and frame",
        "final_visible_fraction" => "share of final samples visible",
        "final_mean_m" => "mean confidence M of the final reservoirs",
        other => other,
    }
}

/// Four significant digits, without a trailing run of zeros for whole numbers.
fn significant(v: f64) -> String {
    if v.is_finite() && v == v.trunc() && v.abs() < 1e9 {
        format!("{v:.0}")
    } else if v != 0.0 && v.is_finite() && (v.abs() < 1e-3 || v.abs() >= 1e5) {
        format!("{v:.3e}")
    } else {
        format!("{v:.4}")
    }
}

/// Each run's GPU time per pass (medians over its repeats): where the time goes.
fn pass_times(runs: &[&RunRecord]) -> String {
    let with: Vec<&&RunRecord> = runs
        .iter()
        .filter(|r| r.pass_gpu_ms.values().any(Option::is_some))
        .collect();
    if with.is_empty() {
        return String::new();
    }
    let mut md = String::from("GPU ms per pass (median over the run's repeats):\n\n");
    for r in with {
        let passes: Vec<String> = r
            .pass_gpu_ms
            .iter()
            .map(|(name, ms)| format!("{name} {}", fixed(*ms, 2)))
            .collect();
        let _ = writeln!(md, "- {} {}: {}", r.label, r.budget, passes.join(", "));
    }
    md + "\n"
}

/// Marks the time of a run whose time budget cannot be met on this device (results.rs,
/// `budget_missed`); a footnote under the table gives the times.
pub const MISSED_MARK: &str = " †";

fn missed_mark(r: &RunRecord) -> &'static str {
    if r.budget_missed || off_budget(r).is_some() {
        MISSED_MARK
    } else {
        ""
    }
}

/// A run whose time budget was met in count but not in time: its time (GPU, or wall without
/// timestamps) over the budget by more than `OFF_BUDGET` or under it by as much (the
/// calibration's line predicted the count poorly). The ratio, its time and which clock; None
/// within the band, for runs without a time budget, and for runs that cannot meet it at all
/// (`budget_missed`, said apart).
fn off_budget(r: &RunRecord) -> Option<(f64, f64, &'static str)> {
    if r.budget_missed || r.status != Status::Ok {
        return None;
    }
    let budget = r.time_ms.or(r.frame_ms)?;
    let (t, clock) = r
        .gpu_ms
        .map(|t| (t, "GPU"))
        .or(r.wall_ms.map(|t| (t, "wall")))?;
    let ratio = t / budget;
    (!(1.0 / OFF_BUDGET..=OFF_BUDGET).contains(&ratio)).then_some((ratio, t, clock))
}

/// How far from its time budget a calibrated run may land unmarked: 1.25x over or under.
pub const OFF_BUDGET: f64 = 1.25;

/// One footnote line per run whose time budget was missed; empty when none was.
fn missed_footnotes(runs: &[&RunRecord]) -> String {
    let mut md = String::new();
    for r in runs.iter().filter(|r| r.budget_missed) {
        let took = r
            .gpu_ms
            .map(|t| (t, "GPU"))
            .or(r.wall_ms.map(|t| (t, "wall")));
        let _ = writeln!(
            md,
            "{} {} budget missed: {} {} took {} {} ms{} at a count of 1, over its budget of {} ms; \
             no count meets it on this device, so its figures are not at equal time.\n",
            MISSED_MARK.trim(),
            if r.frame_ms.is_some() { "Frame-time" } else { "Time" },
            r.label,
            r.budget,
            fixed(took.map(|t| t.0), 3),
            took.map(|t| t.1).unwrap_or("GPU"),
            if r.frame_ms.is_some() { " a frame" } else { "" },
            r.time_ms
                .or(r.frame_ms)
                .map(|t| t.to_string())
                .unwrap_or_else(|| "-".into()),
        );
    }
    for r in runs.iter() {
        let Some((ratio, t, clock)) = off_budget(r) else {
            continue;
        };
        let _ =
            writeln!(
            md,
            "{} {} budget {}: {} {} took {} {clock} ms{}, {:.2}x its budget of {} ms (calibrated \
             count {}): compare it with the others at its own time, not at the budget's.\n",
            MISSED_MARK.trim(),
            if r.frame_ms.is_some() { "Frame-time" } else { "Time" },
            if ratio < 1.0 { "undershot" } else { "overshot" },
            r.label,
            r.budget,
            fixed(Some(t), 3),
            if r.frame_ms.is_some() { " a frame" } else { "" },
            ratio,
            r.time_ms
                .or(r.frame_ms)
                .map(|t| t.to_string())
                .unwrap_or_else(|| "-".into()),
            r.calibrated_count
                .map(|c| c.to_string())
                .unwrap_or_else(|| "-".into()),
        );
    }
    md
}

/// The run's relMSE less the reference's own (estimated from its halves; references.rs): the
/// expected squared error against the reference adds the reference's variance to the run's
/// error against the converged image, so the difference estimates the latter. None without
/// figures; the reference's own taken as 0 when unknown.
fn net_rel_mse(r: &RunRecord) -> Option<f64> {
    Some(r.metrics?.rel_mse - r.reference_rel_mse.unwrap_or(0.0))
}

/// Marks a relMSE within `LIMITED_FACTOR` of the reference's own: the reference's noise, not
/// the run, sets that figure.
pub const LIMITED_MARK: &str = " ‡";
pub const LIMITED_FACTOR: f64 = 10.0;

fn limited_by_reference(r: &RunRecord) -> bool {
    match (r.metrics, r.reference_rel_mse) {
        (Some(m), Some(floor)) => m.rel_mse < LIMITED_FACTOR * floor,
        _ => false,
    }
}

/// `v` with `digits` decimals, "-" where missing or not finite.
pub(super) fn fixed(v: Option<f64>, digits: usize) -> String {
    match v {
        Some(x) if x.is_finite() => format!("{x:.digits$}"),
        _ => "-".into(),
    }
}

fn sci(v: Option<f64>) -> String {
    match v {
        Some(x) if x.is_finite() => format!("{x:.3e}"),
        _ => "-".into(),
    }
}

fn percent(v: Option<f64>) -> String {
    match v {
        Some(x) if x.is_finite() => format!("{:.2}%", 100.0 * x),
        _ => "-".into(),
    }
}

fn signed_percent(v: Option<f64>) -> String {
    match v {
        Some(x) if x.is_finite() => format!("{:+.2}%", 100.0 * x),
        _ => "-".into(),
    }
}

/// A table cell: no pipes or line breaks.
fn escape(s: &str) -> String {
    s.replace('|', "\\|").replace('\n', " ")
}

#[cfg(test)]
mod tests {
    use super::super::results::tests::run;
    use super::*;

    fn timed(label: &str, budget: f64, gpu_ms: f64, rel_mse: f64) -> RunRecord {
        let mut r = run("s", "gpu", gpu_ms, rel_mse);
        r.label = label.into();
        r.budget = format!("time_ms={budget}");
        r.time_ms = Some(budget);
        r.calibrated_count = Some(8);
        r
    }

    /// At each budget the summary names the winner by relMSE x GPU time among the plausible
    /// runs and its lead over the next method; a wrong image cannot win.
    #[test]
    fn the_summary_names_each_budgets_winner_among_plausible_runs() {
        let a = timed("ir", 100.0, 100.0, 0.01);
        let b = timed("bir", 100.0, 100.0, 0.04);
        let mut black = timed("broken", 100.0, 100.0, 0.001);
        black.metrics.as_mut().unwrap().bias = 0.99;
        let c = timed("bir", 400.0, 400.0, 0.01);
        let text = summary(&[&a, &b, &black, &c]);
        assert!(
            text.contains("at 100 ms ir wins, 4.00x ahead of bir"),
            "{text}"
        );
        assert!(
            text.contains("at 400 ms bir (the only plausible run)"),
            "{text}"
        );
        assert!(!text.contains("broken"), "{text}");
        // A run within the reference's noise (net relMSE <= 0) ranks by its relMSE, and a
        // run without GPU times by its wall time: both are in.
        let mut limited = timed("restir", 50.0, 50.0, 0.001);
        limited.reference_rel_mse = Some(0.002);
        let mut no_timestamps = timed("env", 50.0, 50.0, 0.01);
        no_timestamps.gpu_ms = None;
        no_timestamps.wall_ms = Some(50.0);
        let text = summary(&[&limited, &no_timestamps]);
        assert!(
            text.contains("at 50 ms restir wins, 10.00x ahead of env"),
            "{text}"
        );
        let mut declined = timed("ir", 70.0, 70.0, 0.01);
        declined.status = Status::Declined;
        declined.metrics = None;
        assert!(summary(&[&declined]).contains("at 70 ms no run was scored"));
        // Count budgets: the starred runs.
        let mut d = run("s", "gpu", 5.0, 0.1);
        d.pareto = true;
        d.budget = "spp=4".into();
        let text = summary(&[&d]);
        assert!(text.contains("pt spp=4"), "{text}");
    }

    /// A calibrated run that lands outside 1.25x of its budget, under or over, is marked and
    /// footnoted; within the band, or with a count budget, it is not.
    #[test]
    fn off_budget_runs_are_marked_both_ways() {
        let under = timed("ir", 500.0, 281.0, 0.1);
        let over = timed("bir", 500.0, 700.0, 0.1);
        let fine = timed("pt", 500.0, 480.0, 0.1);
        let count = run("s", "gpu", 1.0, 0.1);
        assert_eq!(missed_mark(&under), MISSED_MARK);
        assert_eq!(missed_mark(&over), MISSED_MARK);
        assert_eq!(missed_mark(&fine), "");
        assert_eq!(missed_mark(&count), "");
        let notes = missed_footnotes(&[&under, &over, &fine, &count]);
        assert!(notes.contains("budget undershot: ir"), "{notes}");
        assert!(notes.contains("0.56x its budget of 500 ms"), "{notes}");
        assert!(notes.contains("budget overshot: bir"), "{notes}");
        assert_eq!(notes.matches(MISSED_MARK.trim()).count(), 2, "{notes}");
    }

    /// Method figures are grouped by method and named for people, the key kept beside.
    #[test]
    fn method_figures_are_grouped_and_named() {
        let mut a = timed("bir", 100.0, 90.0, 0.1);
        a.method = "bir".into();
        a.stats.insert("kept_standard_fraction".into(), 0.25);
        let mut b = timed("ir-reuse", 100.0, 90.0, 0.1);
        b.method = "ir".into();
        b.stats.insert("reuse_kept_paths".into(), 96.0);
        b.stats.insert("some_new_figure".into(), 1.5e-5);
        let mut c = timed("bir-2", 200.0, 190.0, 0.1);
        c.method = "bir".into();
        c.stats.insert("kept_standard_fraction".into(), 0.5);
        let text = method_figures(&[&a, &b, &c]);
        let bir = text.find("- **bir**").unwrap();
        let ir = text.find("- **ir**").unwrap();
        assert!(bir < ir, "{text}");
        assert!(text.contains(
            "  - bir-2 time_ms=200: share of standard VPLs kept 0.5000 (`kept_standard_fraction`)"
        ));
        assert!(text.contains("light paths kept from earlier frames 96 (`reuse_kept_paths`)"));
        assert!(
            text.contains("some_new_figure 1.500e-5 (`some_new_figure`)"),
            "{text}"
        );
        assert_eq!(method_figures(&[&run("s", "gpu", 1.0, 0.1)]), "");
    }

    #[test]
    fn pass_times_list_each_runs_passes() {
        let mut r = timed("ir", 100.0, 90.0, 0.1);
        r.pass_gpu_ms.insert("gbuffer".into(), Some(1.25));
        r.pass_gpu_ms.insert("vpl gather".into(), None);
        let text = pass_times(&[&r]);
        assert!(
            text.contains("- ir time_ms=100: gbuffer 1.25, vpl gather -"),
            "{text}"
        );
        assert_eq!(pass_times(&[&run("s", "gpu", 1.0, 0.1)]), "");
    }
}
