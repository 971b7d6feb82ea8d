//! A suite's results: one `RunRecord` per run (every parameter and figure, device and driver),
//! gathered in `SuiteResults`, written as results.json (the source every other output and
//! `bench merge` read) and results.csv (one row per run, for spreadsheets and plotting
//! scripts). The Pareto marks are computed here, per scene, over GPU time and relMSE.

use std::collections::{BTreeMap, BTreeSet};
use std::fs;
use std::path::Path;

use anyhow::{bail, Context as _, Result};
use serde::{Deserialize, Serialize};

use crate::image::Metrics;

use super::calibrate::Trial;
use super::file::Shard;

/// What became of a run.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Status {
    /// Rendered and scored.
    Ok,
    /// The method does not handle something in the scene (recorded with its reason).
    Declined,
    /// Rendering failed (recorded with the error); the suite went on.
    Error,
    /// The device cannot hold the scene (methods/device_fit.rs; the note says why, in the
    /// scene's words): every run of the scene is refused before anything is built.
    Refused,
}

impl Status {
    pub fn as_str(self) -> &'static str {
        match self {
            Status::Ok => "ok",
            Status::Declined => "declined",
            Status::Error => "error",
            Status::Refused => "refused",
        }
    }
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RunRecord {
    /// Position in the whole suite (shards keep it, so merged parts sort back in order).
    pub index: usize,
    pub id: String,
    pub scene: String,
    /// The scene file as the suite names it (`embedded:cornell-box` for the built-in one).
    pub scene_path: String,
    pub scene_hash: String,
    pub method: String,
    pub label: String,
    pub budget: String,
    /// A time budget's GPU milliseconds (suite `time_ms`), None for a fixed count.
    #[serde(default)]
    pub time_ms: Option<f64>,
    /// The count (frames, or the reference's spp) the time budget calibrated; the run
    /// rendered with it, and `parameters` holds it.
    #[serde(default)]
    pub calibrated_count: Option<u32>,
    /// The calibration renders behind `calibrated_count` (calibrate.rs).
    #[serde(default)]
    pub calibration: Vec<Trial>,
    /// The time budget cannot be met on this device: even at a count of 1 the run took longer
    /// (`gpu_ms`, or `wall_ms` without timestamps), so its figures are not at equal time.
    #[serde(default)]
    pub budget_missed: bool,
    pub parameters: BTreeMap<String, serde_json::Value>,
    pub status: Status,
    /// Why a run was declined or failed.
    pub note: String,
    /// The scene's `[failure]` table names this method.
    pub expected_failure: bool,
    /// The suite names this run's label among the scene's `home` methods (the ones it
    /// showcases).
    #[serde(default)]
    pub home: bool,
    pub resolution: [u32; 2],
    /// Seed of the first timed repeat (repeat r used seed + r).
    pub seed: u32,
    pub warmup: u32,
    pub repeats: u32,
    /// Frames (successive seeds) the flicker is measured over; 0 for none.
    pub flicker_frames: u32,
    /// Frames a frame-time run rendered, unscored, before each sequence's scored frames (the
    /// suite's `lead_in` for a method that carries state across frames, as many as the
    /// animation had; 0 otherwise).
    #[serde(default)]
    pub lead_in: u32,
    /// Images whose figures are averaged in `metrics`: max(repeats, flicker_frames).
    pub scored: u32,
    pub device: String,
    pub driver: String,
    /// Median over the repeats of the run's total GPU time; None without timestamps.
    pub gpu_ms: Option<f64>,
    /// Median over the repeats of each pass's GPU time.
    pub pass_gpu_ms: BTreeMap<String, Option<f64>>,
    /// Median over the repeats of the wall-clock time (upload excluded, readback included).
    pub wall_ms: Option<f64>,
    /// Against the reference, each figure averaged over the scored images.
    pub metrics: Option<Metrics>,
    /// Mean over pixels and channels of the temporal standard deviation across the repeats'
    /// images (successive seeds) relative to the reference (`image::metrics::flicker`).
    pub flicker: Option<f64>,
    /// The mean over the scored images (successive seeds) of the image mean, relative to the
    /// reference's, minus 1 (signed; measure.rs).
    #[serde(default)]
    pub image_mean_offset: Option<f64>,
    /// The standard deviation over the scored images of the image mean relative to the
    /// reference's (measure.rs): how far one render's brightness moves from the next's.
    #[serde(default)]
    pub image_mean_spread: Option<f64>,
    /// The lowest and highest relMSE of the scored images (`metrics.rel_mse` is their mean):
    /// the bar through the run's point in its scene's chart.
    #[serde(default)]
    pub rel_mse_min: Option<f64>,
    #[serde(default)]
    pub rel_mse_max: Option<f64>,
    /// Per-pixel estimates the method dropped as NaN or Inf, over all repeats (0 when right).
    pub nonfinite_estimates: u64,
    pub reference_spp: u32,
    pub reference_seed: u32,
    /// The reference's own relMSE, estimated from its two halves: a run's relMSE cannot be
    /// measured much below it (the report flags runs within 10x of it).
    pub reference_rel_mse: Option<f64>,
    /// The run's thumbnail and error map, relative to the output folder.
    pub image: Option<String>,
    pub error_map: Option<String>,
    /// On the per-scene Pareto front of (GPU time, relMSE) among the ok runs.
    #[serde(default)]
    pub pareto: bool,
    /// The method's own figures (bir: kept fractions per side, rays per kept VPL), averaged
    /// over the scored images.
    #[serde(default)]
    pub stats: BTreeMap<String, f64>,
    /// A frame-time budget (`frame_ms`) on an animated scene: GPU milliseconds per frame the
    /// count was calibrated to. `gpu_ms` and `wall_ms` are then the median frame's, and
    /// `metrics` the mean over frames (and seeds) of each frame against its own reference.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub frame_ms: Option<f64>,
    /// A frame-time run's figures per frame, worst frame and flicker.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sequence: Option<SequenceResult>,
}

/// What a frame-time run (`frame_ms`) measured over its animation frames: it rendered every
/// frame of `frames` once per seed (its `repeats` seeds: sequence r uses the run's seed +
/// r x `frames[1]`, frame f of it that + f, `sequence::frame_seed`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SequenceResult {
    /// Frames A (included) to B (not).
    pub frames: [u32; 2],
    /// The frame the count was calibrated on.
    pub calibration_frame: u32,
    /// Per frame, in order: each figure the mean over the seeds, the GPU time their median.
    pub per_frame: Vec<FrameResult>,
    /// The frame with the highest relMSE (of `per_frame`), and that relMSE (None where it is
    /// not finite).
    pub worst_frame: u32,
    pub worst_rel_mse: Option<f64>,
    /// The flicker of the sequence (docs/DESIGN.md "Error metrics": the temporal change of
    /// the error from frame to frame relative to the reference's own change), the mean over
    /// the seeds; None for one frame (or where a frame has NaN/Inf).
    pub flicker: Option<f64>,
}

/// One frame of a frame-time run.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct FrameResult {
    pub frame: u32,
    /// Against the frame's own reference, averaged over the run's seeds.
    pub metrics: Metrics,
    /// GPU time of the frame (median over the seeds); NaN, `null` in JSON, where the device
    /// has no timestamps.
    #[serde(with = "crate::image::metrics::nullable_f64")]
    pub gpu_ms: f64,
}

/// One frame's reference of an animated scene.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct FrameReference {
    pub frame: u32,
    pub spp: u32,
    /// Its own relMSE, from its two halves.
    pub rel_mse: Option<f64>,
    /// Stored beside the scene by `irad bench references` (else the cache's, rendered now
    /// when missing).
    pub converged: bool,
    /// Where it was read from (or written to).
    pub path: String,
}

/// Everything a suite (or one shard of it) produced so far.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SuiteResults {
    pub suite: String,
    pub suite_file: String,
    pub suite_hash: String,
    pub description: String,
    /// The part of the suite these results cover; None once merged.
    pub shard: Option<Shard>,
    /// Runs in the whole suite, and those this shard plans.
    pub runs_in_suite: usize,
    pub runs_planned: usize,
    /// False while the suite is running or when it was interrupted.
    pub complete: bool,
    pub device: String,
    pub driver: String,
    pub irad_version: String,
    /// Per scene: its reference image (relative path), spp and where it is cached.
    pub references: BTreeMap<String, ReferenceSummary>,
    pub runs: Vec<RunRecord>,
    /// The suite file's text, so that a run refused after an edit can name the field that
    /// changed; empty in results written before it was recorded.
    #[serde(default)]
    pub suite_text: String,
    /// Every scene of the suite in suite order, so that a run refused after an edit can name
    /// the scene whose contents changed; empty in results written before it was recorded.
    #[serde(default)]
    pub scene_files: Vec<SceneFile>,
    /// Per scene the suite uploaded (or the device refused): its size, the upload's CPU
    /// builds and its device memory.
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub uploads: BTreeMap<String, SceneUpload>,
}

/// A scene as the suite uploaded it once for its runs (an animated scene: its calibration
/// frame): what the samplers choose among, what its CPU builds took and what its data takes on
/// the device; or the device's refusal.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SceneUpload {
    pub triangles: u64,
    /// Emissive triangles, point and spot lights (the light BVH's leaves).
    pub lights: u64,
    /// Wall milliseconds loading the scene took when the suite was loaded.
    pub load_ms: f64,
    /// The upload's CPU builds (`GpuScene::build_ms`): the triangle BVH and the light BVH.
    pub triangle_bvh_ms: Option<f64>,
    pub light_bvh_ms: Option<f64>,
    /// Device bytes of the light data (light table, emitters, light BVH nodes and trails) and
    /// of everything the scene uploads (`GpuScene::light_bytes`, `device_bytes`).
    pub light_bytes: Option<u64>,
    pub device_bytes: Option<u64>,
    /// The device's refusal (methods/device_fit.rs), where it cannot hold the scene.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub refused: Option<String>,
}

/// A scene of a suite as it was run.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SceneFile {
    pub name: String,
    /// As the suite file writes it.
    pub path: String,
    /// `Scene::content_hash`, 16 hex digits.
    pub content_hash: String,
    /// A member of a generated family (`path = "generated:NAME"`): its generator and light
    /// count, which the report charts against.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub generated: Option<super::generated::Generated>,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ReferenceSummary {
    pub spp: u32,
    pub image: String,
    pub cache: String,
    pub seed: u32,
    pub gpu_ms: Option<f64>,
    /// The reference's own relMSE, estimated from its two halves (references.rs).
    pub rel_mse: Option<f64>,
    /// Read from the converged reference stored beside the scene (`irad bench references`)
    /// rather than the cache.
    #[serde(default)]
    pub converged: bool,
    /// The scene's `[failure]` table: methods expected to fail, why, and the paper figure.
    pub expected_to_fail: Vec<String>,
    pub why: String,
    pub source: String,
    /// For an animated scene: one reference per frame (the fields above describe the
    /// calibration frame's, whose thumbnail is `image`).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub frames: Vec<FrameReference>,
}

/// A run is starred (Pareto-optimal) only where its image is plausibly right: its bias (the
/// image mean's offset from the reference's, over its renders) at most this...
pub const STAR_MAX_BIAS: f64 = 0.10;
/// ...and at most this share of its pixels outliers (10x the reference plus 0.1). A black image
/// or one of fireflies can be fast and "least wrong" among broken runs; it is never the best.
pub const STAR_MAX_OUTLIERS: f64 = 0.01;

/// Whether `r` ran and its image is plausibly right: no NaN or Inf (in its images or dropped
/// as estimates), its bias and outlier share within the star's thresholds. Only such runs are
/// starred or named in a report's summary.
pub fn plausible(r: &RunRecord) -> bool {
    r.status == Status::Ok
        && r.nonfinite_estimates == 0
        && r.metrics.is_some_and(|m| {
            m.nan_inf == 0 && m.bias <= STAR_MAX_BIAS && m.outliers <= STAR_MAX_OUTLIERS
        })
}

impl SuiteResults {
    pub fn read(path: &Path) -> Result<SuiteResults> {
        let text =
            fs::read_to_string(path).with_context(|| format!("reading {}", path.display()))?;
        serde_json::from_str(&text)
            .with_context(|| format!("parsing {} as irad suite results", path.display()))
    }

    /// Scene names in the order their first run appears.
    pub fn scenes(&self) -> Vec<String> {
        let mut seen = Vec::new();
        for r in &self.runs {
            if !seen.contains(&r.scene) {
                seen.push(r.scene.clone());
            }
        }
        seen
    }

    /// Marks, per scene and device, the ok runs no other ok run beats in both GPU time and
    /// relMSE (at least as good in both, better in one). A run that produced any NaN or Inf
    /// is never marked (its relMSE leaves those values out).
    pub fn mark_pareto(&mut self) {
        let point = |r: &RunRecord| -> Option<(f64, f64)> {
            let t = r.gpu_ms?;
            let e = r.metrics?.rel_mse;
            (plausible(r) && t.is_finite() && e.is_finite()).then_some((t, e))
        };
        let points: Vec<Option<(f64, f64)>> = self.runs.iter().map(point).collect();
        for i in 0..self.runs.len() {
            let Some((t, e)) = points[i] else {
                self.runs[i].pareto = false;
                continue;
            };
            let dominated = (0..self.runs.len()).any(|j| {
                j != i
                    && self.runs[j].scene == self.runs[i].scene
                    && self.runs[j].device == self.runs[i].device
                    && points[j].is_some_and(|(tj, ej)| tj <= t && ej <= e && (tj < t || ej < e))
            });
            self.runs[i].pareto = !dominated;
        }
    }

    pub fn json(&self) -> String {
        let mut text = serde_json::to_string_pretty(self).expect("results serialize");
        text.push('\n');
        text
    }

    /// The CSV: the fixed `COLUMNS`, then `param:<name>` for every parameter any run has,
    /// `pass_ms:<name>` for every pass and `stat:<name>` for every stat, each in name order.
    /// Empty cells for undefined figures. The header and every row are written from one list
    /// of columns.
    pub fn csv(&self) -> String {
        let params: BTreeSet<&str> = self
            .runs
            .iter()
            .flat_map(|r| r.parameters.keys().map(String::as_str))
            .collect();
        let passes: BTreeSet<&str> = self
            .runs
            .iter()
            .flat_map(|r| r.pass_gpu_ms.keys().map(String::as_str))
            .collect();
        let stats: BTreeSet<&str> = self
            .runs
            .iter()
            .flat_map(|r| r.stats.keys().map(String::as_str))
            .collect();
        let mut columns: Vec<(String, Cell)> = COLUMNS
            .iter()
            .map(|&(name, cell)| (name.to_string(), Box::new(cell) as Cell))
            .collect();
        for p in params {
            let cell = move |r: &RunRecord| match r.parameters.get(p) {
                Some(serde_json::Value::String(s)) => s.clone(),
                Some(v) => v.to_string(),
                None => String::new(),
            };
            columns.push((format!("param:{p}"), Box::new(cell)));
        }
        for p in passes {
            let cell = move |r: &RunRecord| figure(r.pass_gpu_ms.get(p).copied().flatten());
            columns.push((format!("pass_ms:{p}"), Box::new(cell)));
        }
        for p in stats {
            let cell = move |r: &RunRecord| figure(r.stats.get(p).copied());
            columns.push((format!("stat:{p}"), Box::new(cell)));
        }
        let header: Vec<String> = columns.iter().map(|(name, _)| name.clone()).collect();
        let mut out = csv_row(&header);
        for r in &self.runs {
            let row: Vec<String> = columns.iter().map(|(_, cell)| cell(r)).collect();
            out += &csv_row(&row);
        }
        out
    }
}

/// How a CSV column writes a run's cell.
type Cell<'a> = Box<dyn Fn(&RunRecord) -> String + 'a>;

/// A figure's cell: empty when undefined (None, NaN or infinite).
fn figure(v: Option<f64>) -> String {
    v.filter(|x| x.is_finite())
        .map(|x| x.to_string())
        .unwrap_or_default()
}

/// A fixed CSV column: its header, and how a run's cell is written.
type Column = (&'static str, fn(&RunRecord) -> String);

/// The CSV's fixed columns, in order. The header and every row come from this one table, so a
/// column cannot be added to one and not the other.
const COLUMNS: &[Column] = &[
    ("index", |r| r.index.to_string()),
    ("id", |r| r.id.clone()),
    ("scene", |r| r.scene.clone()),
    ("scene_path", |r| r.scene_path.clone()),
    ("method", |r| r.method.clone()),
    ("label", |r| r.label.clone()),
    ("budget", |r| r.budget.clone()),
    ("time_ms", |r| figure(r.time_ms)),
    ("calibrated_count", |r| {
        r.calibrated_count
            .map(|c| c.to_string())
            .unwrap_or_default()
    }),
    ("budget_missed", |r| r.budget_missed.to_string()),
    ("status", |r| r.status.as_str().to_string()),
    ("expected_failure", |r| r.expected_failure.to_string()),
    ("home", |r| r.home.to_string()),
    ("pareto", |r| r.pareto.to_string()),
    ("width", |r| r.resolution[0].to_string()),
    ("height", |r| r.resolution[1].to_string()),
    ("seed", |r| r.seed.to_string()),
    ("warmup", |r| r.warmup.to_string()),
    ("repeats", |r| r.repeats.to_string()),
    ("flicker_frames", |r| r.flicker_frames.to_string()),
    ("scored", |r| r.scored.to_string()),
    ("gpu_ms", |r| figure(r.gpu_ms)),
    ("wall_ms", |r| figure(r.wall_ms)),
    ("rel_mse", |r| figure(r.metrics.map(|m| m.rel_mse))),
    ("rel_mse_min", |r| figure(r.rel_mse_min)),
    ("rel_mse_max", |r| figure(r.rel_mse_max)),
    ("rmse", |r| figure(r.metrics.map(|m| m.rmse))),
    ("lab_error", |r| figure(r.metrics.map(|m| m.lab_error))),
    ("bias", |r| figure(r.metrics.map(|m| m.bias))),
    ("outliers", |r| figure(r.metrics.map(|m| m.outliers))),
    ("nan_inf", |r| {
        r.metrics.map(|m| m.nan_inf.to_string()).unwrap_or_default()
    }),
    ("flicker", |r| figure(r.flicker)),
    ("image_mean_offset", |r| figure(r.image_mean_offset)),
    ("image_mean_spread", |r| figure(r.image_mean_spread)),
    ("nonfinite_estimates", |r| r.nonfinite_estimates.to_string()),
    ("reference_spp", |r| r.reference_spp.to_string()),
    ("reference_seed", |r| r.reference_seed.to_string()),
    ("reference_rel_mse", |r| figure(r.reference_rel_mse)),
    ("device", |r| r.device.clone()),
    ("driver", |r| r.driver.clone()),
    ("scene_hash", |r| r.scene_hash.clone()),
    ("note", |r| r.note.clone()),
    // Frame-time runs (animated scenes); after the older columns, which keep their places.
    ("frame_ms", |r| figure(r.frame_ms)),
    ("frames", |r| {
        r.sequence
            .as_ref()
            .map(|s| format!("{}..{}", s.frames[0], s.frames[1]))
            .unwrap_or_default()
    }),
    ("worst_frame", |r| {
        r.sequence
            .as_ref()
            .map(|s| s.worst_frame.to_string())
            .unwrap_or_default()
    }),
    ("worst_frame_rel_mse", |r| {
        figure(r.sequence.as_ref().and_then(|s| s.worst_rel_mse))
    }),
    ("sequence_flicker", |r| {
        figure(r.sequence.as_ref().and_then(|s| s.flicker))
    }),
    // HDR-FLIP, where the run scored it (frame-time runs: the mean over frames and seeds).
    ("flip", |r| figure(r.metrics.and_then(|m| m.flip))),
    ("lead_in", |r| r.lead_in.to_string()),
];

/// The CSV's first columns, in order (the names of `COLUMNS`).
pub const FIXED_COLUMNS: &[&str] = &{
    let mut names = [""; COLUMNS.len()];
    let mut i = 0;
    while i < COLUMNS.len() {
        names[i] = COLUMNS[i].0;
        i += 1;
    }
    names
};

/// One RFC 4180 row: fields with a comma, quote or line break are quoted, quotes doubled.
fn csv_row(fields: &[String]) -> String {
    let mut line = fields
        .iter()
        .map(|f| {
            if f.contains([',', '"', '\n', '\r']) {
                format!("\"{}\"", f.replace('"', "\"\""))
            } else {
                f.clone()
            }
        })
        .collect::<Vec<_>>()
        .join(",");
    line.push('\n');
    line
}

/// Parses CSV as `csv` writes it (RFC 4180: quoted fields, doubled quotes, line breaks inside
/// quotes) into rows of fields.
pub fn parse_csv(text: &str) -> Result<Vec<Vec<String>>> {
    let mut rows = Vec::new();
    let mut row = Vec::new();
    let mut field = String::new();
    let mut chars = text.chars().peekable();
    let mut quoted = false;
    let mut line = 1;
    while let Some(c) = chars.next() {
        if quoted {
            match c {
                '"' if chars.peek() == Some(&'"') => {
                    chars.next();
                    field.push('"');
                }
                '"' => quoted = false,
                c => {
                    if c == '\n' {
                        line += 1;
                    }
                    field.push(c)
                }
            }
            continue;
        }
        match c {
            '"' if field.is_empty() => quoted = true,
            '"' => bail!("line {line}: a quote inside an unquoted field"),
            ',' => row.push(std::mem::take(&mut field)),
            '\r' => {}
            '\n' => {
                row.push(std::mem::take(&mut field));
                rows.push(std::mem::take(&mut row));
                line += 1;
            }
            c => field.push(c),
        }
    }
    if quoted {
        bail!("line {line}: a quoted field is not closed");
    }
    if !field.is_empty() || !row.is_empty() {
        row.push(field);
        rows.push(row);
    }
    Ok(rows)
}

#[cfg(test)]
pub(super) mod tests {
    use super::*;

    pub(in crate::bench::suite) fn run(
        scene: &str,
        device: &str,
        gpu_ms: f64,
        rel_mse: f64,
    ) -> RunRecord {
        RunRecord {
            index: 0,
            id: format!("{scene}/{gpu_ms}/{rel_mse}"),
            scene: scene.into(),
            scene_path: String::new(),
            scene_hash: String::new(),
            method: "reference".into(),
            label: "pt".into(),
            budget: String::new(),
            time_ms: None,
            calibrated_count: None,
            calibration: vec![],
            budget_missed: false,
            parameters: BTreeMap::new(),
            status: Status::Ok,
            note: String::new(),
            expected_failure: false,
            home: false,
            resolution: [1, 1],
            seed: 0,
            warmup: 0,
            repeats: 1,
            flicker_frames: 0,
            lead_in: 0,
            scored: 1,
            device: device.into(),
            driver: String::new(),
            gpu_ms: Some(gpu_ms),
            pass_gpu_ms: BTreeMap::new(),
            wall_ms: None,
            metrics: Some(Metrics {
                rel_mse,
                rmse: 0.0,
                lab_error: 0.0,
                bias: 0.0,
                outliers: 0.0,
                nan_inf: 0,
                flip: None,
            }),
            flicker: None,
            image_mean_offset: None,
            image_mean_spread: None,
            rel_mse_min: None,
            frame_ms: None,
            sequence: None,
            rel_mse_max: None,
            nonfinite_estimates: 0,
            reference_spp: 1,
            reference_seed: 9,
            reference_rel_mse: None,
            image: None,
            error_map: None,
            pareto: false,
            stats: BTreeMap::new(),
        }
    }

    /// A complete suite's results holding `runs` (device "gpu").
    pub(in crate::bench::suite) fn suite_results(runs: Vec<RunRecord>) -> SuiteResults {
        SuiteResults {
            suite: "s".into(),
            suite_file: String::new(),
            suite_hash: String::new(),
            description: String::new(),
            shard: None,
            runs_in_suite: runs.len(),
            runs_planned: runs.len(),
            complete: true,
            device: "gpu".into(),
            driver: String::new(),
            irad_version: String::new(),
            references: BTreeMap::new(),
            runs,
            suite_text: String::new(),
            scene_files: Vec::new(),
            uploads: BTreeMap::new(),
        }
    }

    /// A still scene's reference whose thumbnail is `image`.
    pub(in crate::bench::suite) fn reference_summary(image: &str) -> ReferenceSummary {
        ReferenceSummary {
            spp: 64,
            image: image.into(),
            cache: String::new(),
            seed: 1,
            gpu_ms: None,
            rel_mse: Some(1e-4),
            converged: false,
            expected_to_fail: Vec::new(),
            why: String::new(),
            source: String::new(),
            frames: Vec::new(),
        }
    }

    #[test]
    fn pareto_marks_the_undominated_runs_per_scene_and_device() {
        let mut runs = vec![
            run("a", "gpu", 1.0, 1.0),  // fastest: on the front
            run("a", "gpu", 2.0, 0.5),  // on the front
            run("a", "gpu", 3.0, 0.5),  // same error, slower: dominated
            run("a", "gpu", 2.0, 0.5),  // a tie with the second: both kept
            run("a", "gpu", 4.0, 0.1),  // most accurate: on the front
            run("a", "gpu", 5.0, 2.0),  // dominated by all
            run("b", "gpu", 9.0, 9.0),  // alone in its scene
            run("a", "cpu", 50.0, 5.0), // alone on its device
        ];
        let mut nan = run("a", "gpu", 0.5, 0.01); // would dominate, but produced a NaN
        nan.metrics.as_mut().unwrap().nan_inf = 1;
        runs.push(nan);
        let mut declined = run("a", "gpu", 0.1, 0.001);
        declined.status = Status::Declined;
        runs.push(declined);
        let mut results = suite_results(runs);
        results.mark_pareto();
        let marks: Vec<bool> = results.runs.iter().map(|r| r.pareto).collect();
        assert_eq!(
            marks,
            [true, true, false, true, true, false, true, true, false, false]
        );

        // A plainly wrong image (a black one: bias near 100%; one of fireflies: outliers) is
        // never starred, and does not take the star from the runs it would dominate.
        let mut black = run("a", "gpu", 0.2, 0.05);
        black.metrics.as_mut().unwrap().bias = 0.9997;
        let mut fireflies = run("a", "gpu", 0.3, 0.02);
        fireflies.metrics.as_mut().unwrap().outliers = 0.03;
        let mut edge = run("a", "gpu", 0.4, 0.03);
        edge.metrics.as_mut().unwrap().bias = STAR_MAX_BIAS;
        edge.metrics.as_mut().unwrap().outliers = STAR_MAX_OUTLIERS;
        results.runs.extend([black, fireflies, edge]);
        results.mark_pareto();
        let marks: Vec<bool> = results.runs.iter().map(|r| r.pareto).collect();
        // The run at the thresholds dominates the first five of scene a; the two wrong ones
        // are left out.
        assert_eq!(
            marks,
            [
                false, false, false, false, false, false, true, true, false, false, false, false,
                true
            ]
        );
    }

    #[test]
    fn csv_round_trips_quotes_commas_and_line_breaks() {
        let fields: Vec<String> = ["plain", "a,b", "say \"hi\"", "two\nlines", ""]
            .iter()
            .map(|s| s.to_string())
            .collect();
        let text = csv_row(&fields) + &csv_row(&fields);
        assert_eq!(parse_csv(&text).unwrap(), vec![fields.clone(), fields]);
        assert!(parse_csv("\"open").is_err());
    }

    /// Two runs that between them fill every kind of cell: figures and empty ones, a
    /// parameter, a pass and a stat only one has, text that needs quoting.
    fn csv_sample() -> SuiteResults {
        let mut a = run("cornell-box", "gpu, \"fast\"", 12.5, 0.031);
        a.index = 3;
        a.scene_path = "embedded:cornell-box".into();
        a.budget = "time 20ms".into();
        a.time_ms = Some(20.0);
        a.calibrated_count = Some(7);
        a.parameters.insert("vpls".into(), serde_json::json!(64));
        a.parameters
            .insert("strategy".into(), serde_json::json!("bir"));
        a.pass_gpu_ms.insert("trace".into(), Some(3.25));
        a.pass_gpu_ms.insert("shade".into(), None);
        a.wall_ms = Some(f64::NAN);
        a.flicker = Some(0.002);
        a.image_mean_offset = Some(-0.01);
        a.image_mean_spread = Some(0.05);
        (a.rel_mse_min, a.rel_mse_max) = (Some(0.02), Some(0.04));
        a.reference_rel_mse = Some(1e-5);
        a.image = Some("images/a.png".into());
        a.note = "two\nlines".into();
        a.pareto = true;
        a.home = true;
        a.stats.insert("kept".into(), 0.75);
        let mut b = run("veach", "cpu", 1.0, 0.5);
        b.status = Status::Declined;
        b.expected_failure = true;
        b.metrics = None;
        b.gpu_ms = None;
        b.parameters.insert("spp".into(), serde_json::json!(16));
        let mut results = SuiteResults {
            suite: "s".into(),
            suite_file: String::new(),
            suite_hash: String::new(),
            description: String::new(),
            shard: None,
            runs_in_suite: 2,
            runs_planned: 2,
            complete: true,
            device: "gpu".into(),
            driver: String::new(),
            irad_version: String::new(),
            references: BTreeMap::new(),
            runs: vec![a, b],
            suite_text: String::new(),
            scene_files: Vec::new(),
            uploads: BTreeMap::new(),
        };
        results.runs[1].index = 4;
        results
    }

    /// The header, column by column, and every row has as many fields as it.
    #[test]
    fn csv_header_and_rows_come_from_one_column_list() {
        let text = csv_sample().csv();
        let (header, _) = text.split_once('\n').unwrap();
        assert_eq!(
            header,
            "index,id,scene,scene_path,method,label,budget,time_ms,calibrated_count,budget_missed,\
             status,\
             expected_failure,home,pareto,width,height,seed,warmup,repeats,flicker_frames,scored,\
             gpu_ms,wall_ms,rel_mse,rel_mse_min,rel_mse_max,rmse,lab_error,bias,outliers,nan_inf,flicker,\
             image_mean_offset,image_mean_spread,nonfinite_estimates,reference_spp,reference_seed,\
             reference_rel_mse,device,driver,scene_hash,note,frame_ms,frames,worst_frame,\
             worst_frame_rel_mse,sequence_flicker,flip,lead_in,param:spp,param:strategy,\
             param:vpls,pass_ms:shade,pass_ms:trace,stat:kept"
        );
        assert!(header.starts_with(&FIXED_COLUMNS.join(",")));
        let rows = parse_csv(&text).unwrap();
        assert_eq!(rows.len(), 3);
        for row in &rows {
            assert_eq!(row.len(), rows[0].len());
        }
        assert_eq!(rows[0].len(), COLUMNS.len() + 6);
    }

    /// The rows, byte for byte.
    #[test]
    fn csv_rows_are_unchanged() {
        let text = csv_sample().csv();
        let (_, rows) = text.split_once('\n').unwrap();
        assert_eq!(
            rows,
            "3,cornell-box/12.5/0.031,cornell-box,embedded:cornell-box,reference,pt,time 20ms,\
             20,7,false,ok,false,true,true,1,1,0,0,1,0,1,12.5,,0.031,0.02,0.04,0,0,0,0,0,0.002,-0.01,0.05,0,1,9,\
             0.00001,\
             \"gpu, \"\"fast\"\"\",,,\"two\nlines\",,,,,,,0,,bir,64,,3.25,0.75\n\
             4,veach/1/0.5,veach,,reference,pt,,,,false,declined,true,false,false,1,1,0,0,1,0,1,,,,,,,,,,\
             ,,,,0,1,9,,cpu,,,,,,,,,,0,16,,,,,\n"
        );
    }
}
