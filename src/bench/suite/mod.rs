//! `irad bench suite`: runs every method of a suite file at every budget on every scene,
//! times each run (median of repeats after a warm-up), scores it against the scene's cached
//! reference, measures its flicker, and writes results.json, results.csv, one SVG chart per
//! scene (relMSE against GPU time, log-log) and report.md with thumbnails and error maps.
//! Everything is rewritten after each run (write then rename), so an interrupted suite leaves
//! readable results of the runs it finished, and running it again into the same folder resumes
//! it (resume.rs). The folder is locked while a suite writes it (`crate::lock`). `--shard i/n`
//! runs part of a suite; `merge` combines parts.

pub mod calibrate;
pub mod converged;
pub mod eta;
pub mod file;
pub mod generated;
pub mod html;
pub mod measure;
pub mod merge;
pub mod output;
pub mod references;
pub mod report;
pub mod results;
pub mod resume;
pub mod scale;
pub mod sequence;

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};

use anyhow::Result;

use crate::gpu::{Context, GpuError};
use crate::image::{self, preview, sidecar::IRAD_VERSION, Image};
use crate::methods::reference::Reference;
use crate::methods::{Method, Renderers};
use crate::scene::gpu::GpuScene;

pub use file::{Shard, Suite};
use measure::{measure, MeasureError};
pub use results::{ReferenceSummary, RunRecord, SceneFile, SceneUpload, Status, SuiteResults};

/// Thumbnails in the report are at most this wide (block averages of the render).
pub const THUMBNAIL_WIDTH: u32 = 256;

pub struct SuiteOptions {
    /// The output folder.
    pub out: PathBuf,
    /// Root of the reference cache.
    pub cache: PathBuf,
    pub shard: Shard,
    /// Set (by a Ctrl-C handler) to stop after the run under way; the results say incomplete.
    pub stop: Option<&'static AtomicBool>,
    /// Only render (or find) the references of this shard's scenes; no runs.
    pub references_only: bool,
}

/// What the suite is doing, for progress bars.
pub enum Event<'a> {
    /// The reference of `scene`: `done` of `total` samples; `cached` when it was reused.
    Reference {
        scene: &'a str,
        done: u32,
        total: u32,
        cached: bool,
    },
    /// Run `run` of `of` (this shard's count): render `render` of `renders` (warm-up and
    /// repeats; `renders` 0: calibration render `render` of a time budget), `done` of `total`
    /// samples.
    Render {
        run: usize,
        of: usize,
        id: &'a str,
        render: u32,
        renders: u32,
        done: u32,
        total: u32,
    },
    /// The output folder held an interrupted run of this suite: the runs with these indices
    /// (of this shard's `of`) are kept from it and not rendered again.
    Resumed { kept: Vec<usize>, of: usize },
    /// The folder's lock was left by a process that is gone (`holder`); it was taken over.
    StaleLock { holder: String },
    /// `run` of this shard's `of` runs are recorded (kept ones included), the last `record`,
    /// and the outputs rewritten.
    Finished {
        run: usize,
        of: usize,
        record: &'a RunRecord,
    },
}

/// Runs this shard of `suite` into `options.out` and returns the results (also on disk).
pub fn run(
    ctx: &Context,
    suite: &Suite,
    options: &SuiteOptions,
    mut on: impl FnMut(Event),
) -> Result<SuiteResults> {
    let planned = suite.shard(options.shard);
    let info = ctx.info();
    // One writer at a time: a second suite or a merge into this folder is refused.
    let _lock = output::lock(&options.out, &mut |holder| on(Event::StaleLock { holder }))?;
    let previous = resume::check(
        &options.out,
        suite,
        options.shard,
        (&info.name, &info.driver, IRAD_VERSION),
    )?;
    let mut results = SuiteResults {
        suite: suite.name.clone(),
        suite_file: suite.file.clone(),
        suite_hash: format!("{:016x}", suite.hash),
        description: suite.description.clone(),
        shard: (options.shard != Shard::WHOLE).then_some(options.shard),
        runs_in_suite: suite.runs.len(),
        runs_planned: planned.len(),
        complete: false,
        device: info.name.clone(),
        driver: info.driver.clone(),
        irad_version: IRAD_VERSION.into(),
        references: BTreeMap::new(),
        runs: Vec::new(),
        suite_text: suite.text.clone(),
        scene_files: suite
            .scenes
            .iter()
            .map(|s| SceneFile {
                name: s.scene.name.clone(),
                path: s.path.clone(),
                content_hash: format!("{:016x}", s.scene.content_hash),
                generated: s.generated.clone(),
            })
            .collect(),
        uploads: BTreeMap::new(),
    };
    match &previous {
        resume::Previous::Resume(_) if options.references_only => anyhow::bail!(
            "{} holds an interrupted run of this suite; --references-only would replace it: choose another output folder, or run the suite to resume it",
            options.out.display()
        ),
        resume::Previous::Resume(old) => {
            results.runs = resume::kept_runs(old, suite, &planned, &options.out);
            results.references = old.references.clone();
            results.uploads = old.uploads.clone();
            results.mark_pareto();
            on(Event::Resumed {
                kept: results.runs.iter().map(|r| r.index).collect(),
                of: planned.len(),
            });
        }
        resume::Previous::Fresh => {}
    }
    output::prepare(
        &options.out,
        matches!(previous, resume::Previous::Resume(_)),
    )?;
    output::write(&options.out, &results)?;
    let renderers = Renderers::default();
    let stopped = || options.stop.is_some_and(|s| s.load(Ordering::SeqCst));
    if options.references_only {
        // Shard i renders the references of scenes i, i + n, ...: a pre-pass for a sweep
        // whose shards share one cache.
        for (s, _) in suite.scenes.iter().enumerate() {
            if s % options.shard.count == options.shard.index && !stopped() {
                match prepare_scene(ctx, &renderers, suite, s, options, &mut results, &mut on) {
                    // The device cannot hold it: there is no reference to render, and
                    // results.json's uploads say why.
                    Ok(_) | Err(Unprepared::Refused(_)) => {}
                    Err(e) => anyhow::bail!("{}: {e}", suite.scenes[s].scene.name),
                }
            }
        }
        results.runs_planned = 0;
        results.complete = !stopped();
        output::write(&options.out, &results)?;
        return Ok(results);
    }
    let kept: Vec<usize> = results.runs.iter().map(|r| r.index).collect();
    let mut done = kept.len();
    for (s, suite_scene) in suite.scenes.iter().enumerate() {
        let runs: Vec<_> = planned
            .iter()
            .filter(|r| r.scene == s && !kept.contains(&r.index))
            .collect();
        if runs.is_empty() || stopped() {
            continue;
        }
        let scene = &suite_scene.scene;
        // Upload and reference, once per scene; a failure is recorded on every run of it.
        let needs_reference = runs.iter().any(|r| r.method.declines(scene).is_none());
        let prepared = if needs_reference {
            prepare_scene(ctx, &renderers, suite, s, options, &mut results, &mut on)
        } else {
            Err(Unprepared::Failed(
                "every method declines this scene".to_string(),
            ))
        };
        for spec in runs {
            if stopped() {
                break;
            }
            let record = run_one(
                ctx,
                &renderers,
                suite,
                spec,
                &prepared,
                options,
                |r, rs, d, t| {
                    on(Event::Render {
                        run: done,
                        of: planned.len(),
                        id: &spec.id,
                        render: r,
                        renders: rs,
                        done: d,
                        total: t,
                    })
                },
            )?;
            // In suite order, kept runs and new ones alike.
            let at = results.runs.partition_point(|r| r.index < record.index);
            results.runs.insert(at, record);
            results.mark_pareto();
            output::write(&options.out, &results)?;
            done = results.runs.len();
            on(Event::Finished {
                run: done,
                of: planned.len(),
                record: &results.runs[at],
            });
        }
    }
    results.complete = !stopped() && results.runs.len() == results.runs_planned;
    output::write(&options.out, &results)?;
    Ok(results)
}

/// A scene uploaded with its reference image (for an animated scene: its calibration frame
/// uploaded, and one reference per frame of its `frames`), or why not.
type Prepared = std::result::Result<PreparedScene, Unprepared>;

/// Why a scene has no upload and reference for its runs.
enum Unprepared {
    /// The device cannot hold it (methods/device_fit.rs's message): its runs are refused.
    Refused(String),
    /// Uploading it or rendering its reference failed: its runs fail.
    Failed(String),
}

impl From<String> for Unprepared {
    fn from(e: String) -> Unprepared {
        Unprepared::Failed(e)
    }
}

impl std::fmt::Display for Unprepared {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Unprepared::Refused(e) | Unprepared::Failed(e) => f.write_str(e),
        }
    }
}

/// Uploads `scene` (`what`: "the scene", "frame 3"), recording in `results` what the upload
/// took or the device's refusal.
fn upload(
    ctx: &Context,
    suite_scene: &file::SuiteScene,
    scene: &crate::scene::Scene,
    what: &str,
    results: &mut SuiteResults,
) -> std::result::Result<GpuScene, Unprepared> {
    let uploaded = GpuScene::upload(ctx, scene);
    let emissive = scene
        .triangles
        .iter()
        .filter(|t| scene.materials[t.material as usize].is_emissive())
        .count();
    let mut summary = SceneUpload {
        triangles: scene.triangles.len() as u64,
        lights: (emissive + scene.lights.len()) as u64,
        load_ms: suite_scene.load_ms,
        triangle_bvh_ms: None,
        light_bvh_ms: None,
        light_bytes: None,
        device_bytes: None,
        refused: None,
    };
    let outcome = match uploaded {
        Ok(gpu) => {
            summary.triangle_bvh_ms = Some(gpu.build_ms.triangle_bvh);
            summary.light_bvh_ms = Some(gpu.build_ms.light_bvh);
            summary.light_bytes = Some(gpu.light_bytes());
            summary.device_bytes = Some(gpu.device_bytes());
            Ok(gpu)
        }
        Err(GpuError::DoesNotFit(why)) => {
            summary.refused = Some(why.clone());
            Err(Unprepared::Refused(why))
        }
        Err(e) => return Err(Unprepared::Failed(format!("uploading {what}: {e}"))),
    };
    results
        .uploads
        .insert(suite_scene.scene.name.clone(), summary);
    outcome
}

struct PreparedScene {
    gpu: GpuScene,
    reference: Image,
    reference_rel_mse: Option<f64>,
    /// An animated scene's frames, in order: (frame, its reference, the reference's relMSE).
    frames: Vec<(u32, Image, Option<f64>)>,
}

fn prepare_scene(
    ctx: &Context,
    renderers: &Renderers,
    suite: &Suite,
    s: usize,
    options: &SuiteOptions,
    results: &mut SuiteResults,
    on: &mut impl FnMut(Event),
) -> Prepared {
    let suite_scene = &suite.scenes[s];
    let scene = &suite_scene.scene;
    if suite_scene.frames.is_some() {
        return prepare_animated(ctx, renderers, suite, s, options, results, on);
    }
    let gpu_scene = upload(ctx, suite_scene, scene, "the scene", results)?;
    let found = found_reference(ctx, renderers, suite_scene, None, &gpu_scene, options, on)?;
    let converged = found.converged;
    record_reference(options, results, scene, &found, converged, Vec::new())?;
    Ok(PreparedScene {
        gpu: gpu_scene,
        reference: found.image,
        reference_rel_mse: found.rel_mse,
        frames: Vec::new(),
    })
}

/// `prepare_scene` of an animated scene: one reference per frame of the suite's `frames`
/// (each frame's converged reference when `irad bench references` stored one, else the
/// cache's, rendered now when missing, as for a still scene), and the calibration frame
/// uploaded. The summary's own fields describe the calibration frame's reference.
fn prepare_animated(
    ctx: &Context,
    renderers: &Renderers,
    suite: &Suite,
    s: usize,
    options: &SuiteOptions,
    results: &mut SuiteResults,
    on: &mut impl FnMut(Event),
) -> Prepared {
    let suite_scene = &suite.scenes[s];
    let scene = &suite_scene.scene;
    let frames = suite_scene.frames.clone().unwrap_or(0..0);
    let middle = suite_scene.calibration_frame().unwrap_or(0);
    let mut references = Vec::new();
    let mut summaries = Vec::new();
    let mut calibration = None;
    for f in frames {
        let still = scene.at_frame(f).map_err(|e| format!("frame {f}: {e}"))?;
        let gpu = if f == middle {
            upload(ctx, suite_scene, &still, &format!("frame {f}"), results)?
        } else {
            GpuScene::upload(ctx, &still).map_err(|e| match e {
                GpuError::DoesNotFit(why) => Unprepared::Refused(why),
                e => Unprepared::Failed(format!("uploading frame {f}: {e}")),
            })?
        };
        let frame_scene = file::SuiteScene {
            scene: still,
            path: suite_scene.path.clone(),
            reference: suite_scene.reference.clone(),
            home: Vec::new(),
            frames: None,
            entry: suite_scene.entry,
            generated: suite_scene.generated.clone(),
            load_ms: suite_scene.load_ms,
        };
        let found = found_reference(ctx, renderers, &frame_scene, Some(f), &gpu, options, on)
            .map_err(|e| format!("the reference of frame {f}: {e}"))?;
        summaries.push(results::FrameReference {
            frame: f,
            spp: found.spp,
            rel_mse: found.rel_mse,
            converged: found.converged,
            path: found.path.display().to_string(),
        });
        references.push((f, found.image.clone(), found.rel_mse));
        if f == middle {
            calibration = Some((gpu, found));
        }
    }
    let Some((gpu, found)) = calibration else {
        return Err(format!("no frame {middle} among the suite's frames").into());
    };
    let converged = summaries.iter().all(|r| r.converged);
    record_reference(options, results, scene, &found, converged, summaries)?;
    Ok(PreparedScene {
        gpu,
        reference: found.image,
        reference_rel_mse: found.rel_mse,
        frames: references,
    })
}

/// Writes a scene's reference thumbnail (an animated scene's: its calibration frame's) and
/// lists the reference in `results`, with `frames` the per-frame references of an animated one.
fn record_reference(
    options: &SuiteOptions,
    results: &mut SuiteResults,
    scene: &crate::scene::Scene,
    found: &FoundReference,
    converged: bool,
    frames: Vec<results::FrameReference>,
) -> Result<(), String> {
    let image_name = format!("images/{}.reference.png", file::file_safe(&scene.name));
    let thumb = preview::downscale(
        &found.image,
        preview::factor_for(found.image.width, THUMBNAIL_WIDTH),
    );
    image::png::write(&options.out.join(&image_name), &thumb, 0.0).map_err(|e| format!("{e:#}"))?;
    // The full float image beside it, for report.html's viewer (html.rs).
    image::exr::write(&options.out.join(html::exr_of(&image_name)), &found.image)
        .map_err(|e| format!("{e:#}"))?;
    let failure = scene.failure.as_ref();
    results.references.insert(
        scene.name.clone(),
        ReferenceSummary {
            spp: found.spp,
            image: image_name,
            cache: found.path.display().to_string(),
            seed: found.seed,
            gpu_ms: found.gpu_ms,
            rel_mse: found.rel_mse,
            converged,
            expected_to_fail: failure.map(|f| f.methods.clone()).unwrap_or_default(),
            why: failure.map(|f| f.why.clone()).unwrap_or_default(),
            source: failure.map(|f| f.source.clone()).unwrap_or_default(),
            frames,
        },
    );
    Ok(())
}

/// A scene's reference image as the suite found it.
struct FoundReference {
    image: Image,
    spp: u32,
    seed: u32,
    gpu_ms: Option<f64>,
    /// Its own relMSE, from its halves; None for a 1-sample reference.
    rel_mse: Option<f64>,
    /// The file it was read from (or written to).
    path: PathBuf,
    /// Stored beside the scene by `irad bench references` (converged.rs), not the cache's.
    converged: bool,
}

/// The converged reference stored beside the scene when its key matches and it has at least
/// the samples the suite asks for; else the cached one, rendered now when missing.
fn found_reference(
    ctx: &Context,
    renderers: &Renderers,
    suite_scene: &file::SuiteScene,
    frame: Option<u32>,
    gpu_scene: &GpuScene,
    options: &SuiteOptions,
    on: &mut impl FnMut(Event),
) -> std::result::Result<FoundReference, String> {
    let scene = &suite_scene.scene;
    // Progress names the frame of an animated scene.
    let label = match frame {
        Some(f) => format!("{} frame {f}", scene.name),
        None => scene.name.clone(),
    };
    let stored = converged::lookup_frame(scene, &suite_scene.reference, frame)
        .map_err(|e| format!("{e:#}"))?;
    if let Some(c) = stored {
        on(Event::Reference {
            scene: &label,
            done: 1,
            total: 1,
            cached: true,
        });
        let (image, rel_mse) = c.image();
        return Ok(FoundReference {
            image,
            spp: u32::try_from(c.record.total_spp()).unwrap_or(u32::MAX),
            seed: converged::chunk_seed(frame, 0),
            gpu_ms: Some(c.record.gpu_ms),
            rel_mse: Some(rel_mse),
            path: c.halves_path(),
            converged: true,
        });
    }
    // Progress comes only while rendering; a cache hit is reported once it is known.
    let reference = references::get_or_render_frame(
        ctx,
        renderers,
        &options.cache,
        scene,
        frame,
        gpu_scene,
        &suite_scene.reference,
        |done, total| {
            on(Event::Reference {
                scene: &label,
                done,
                total,
                cached: false,
            })
        },
    )
    .map_err(|e| format!("{e:#}"))?;
    if reference.reused {
        on(Event::Reference {
            scene: &label,
            done: 1,
            total: 1,
            cached: true,
        });
    }
    Ok(FoundReference {
        spp: reference_spp(&suite_scene.reference),
        seed: suite_scene.reference.seed().wrapping_add(
            frame
                .unwrap_or(0)
                .wrapping_mul(converged::FRAME_SEED_STRIDE),
        ),
        gpu_ms: reference.record.gpu_ms,
        rel_mse: reference.record.rel_mse,
        path: reference.exr,
        image: reference.image,
        converged: false,
    })
}

fn reference_spp(method: &Method) -> u32 {
    method.settings_of::<Reference>().map_or(0, |s| s.spp)
}

fn run_one(
    ctx: &Context,
    renderers: &Renderers,
    suite: &Suite,
    spec: &file::RunSpec,
    prepared: &Prepared,
    options: &SuiteOptions,
    mut progress: impl FnMut(u32, u32, u32, u32),
) -> Result<RunRecord> {
    let suite_scene = &suite.scenes[spec.scene];
    let scene = &suite_scene.scene;
    let info = ctx.info();
    let mut record = RunRecord {
        index: spec.index,
        id: spec.id.clone(),
        scene: scene.name.clone(),
        scene_path: suite_scene.path.clone(),
        scene_hash: format!("{:016x}", scene.content_hash),
        method: spec.method.name().into(),
        label: suite.entries[spec.entry].label.clone(),
        budget: spec.budget.clone(),
        time_ms: spec.time_ms,
        calibrated_count: None,
        calibration: vec![],
        budget_missed: false,
        parameters: spec.method.parameters(),
        status: Status::Ok,
        note: String::new(),
        expected_failure: scene
            .failure
            .as_ref()
            .is_some_and(|f| f.methods.iter().any(|m| m == spec.method.name())),
        home: suite_scene.home.contains(&suite.entries[spec.entry].label),
        resolution: [scene.camera.width, scene.camera.height],
        seed: spec.method.seed(),
        warmup: suite.warmup,
        repeats: suite.repeats,
        flicker_frames: suite.flicker_frames,
        lead_in: 0,
        scored: 0,
        device: info.name.clone(),
        driver: info.driver.clone(),
        gpu_ms: None,
        pass_gpu_ms: BTreeMap::new(),
        wall_ms: None,
        metrics: None,
        flicker: None,
        image_mean_offset: None,
        image_mean_spread: None,
        rel_mse_min: None,
        rel_mse_max: None,
        nonfinite_estimates: 0,
        reference_spp: reference_spp(&suite_scene.reference),
        reference_seed: suite_scene.reference.seed(),
        reference_rel_mse: None,
        image: None,
        error_map: None,
        pareto: false,
        stats: BTreeMap::new(),
        frame_ms: spec.frame_ms,
        sequence: None,
    };
    if let Some(why) = spec.method.declines(scene) {
        record.status = Status::Declined;
        record.note = why;
        return Ok(record);
    }
    let PreparedScene {
        gpu: gpu_scene,
        reference,
        reference_rel_mse,
        frames: frame_references,
    } = match prepared {
        Ok(p) => p,
        Err(Unprepared::Refused(why)) => {
            record.status = Status::Refused;
            record.note = why.clone();
            return Ok(record);
        }
        Err(Unprepared::Failed(e)) => {
            record.status = Status::Error;
            record.note = format!("no reference: {e}");
            return Ok(record);
        }
    };
    let fail = |mut record: RunRecord, e: MeasureError| {
        match e {
            MeasureError::Declined(why) => {
                record.status = Status::Declined;
                record.note = why;
            }
            MeasureError::Failed(e) => {
                record.status = Status::Error;
                record.note = e;
            }
        }
        Ok(record)
    };
    let mut method = spec.method.clone();
    let calibration_scene;
    let (calibrated_scene, budget_ms) = match (spec.time_ms, spec.frame_ms) {
        (Some(t), _) => (scene, Some(t)),
        (None, Some(f)) => {
            let frame = suite_scene.calibration_frame().unwrap_or(0);
            calibration_scene = match scene.at_frame(frame) {
                Ok(s) => s,
                Err(e) => return fail(record, MeasureError::Failed(format!("frame {frame}: {e}"))),
            };
            (&calibration_scene, Some(f))
        }
        (None, None) => (scene, None),
    };
    if let Some(time_ms) = budget_ms {
        let calibration = calibrate::calibrate(
            ctx,
            renderers,
            &method,
            calibrated_scene,
            gpu_scene,
            time_ms,
            |render, done, total| progress(render, 0, done, total),
        );
        match calibration {
            Ok(c) => {
                method = method.with_count(c.count);
                record.calibrated_count = Some(c.count);
                record.calibration = c.trials;
                record.parameters = method.parameters();
            }
            Err(e) => return fail(record, e),
        }
    }
    if let Some(frame_ms) = spec.frame_ms {
        let frames = suite_scene.frames.clone().unwrap_or(0..0);
        let measured = sequence::measure_sequence(
            ctx,
            renderers,
            &method,
            scene,
            calibrated_scene,
            gpu_scene,
            frames,
            suite_scene.calibration_frame().unwrap_or(0),
            frame_references,
            suite.warmup,
            suite.repeats,
            suite.lead_in,
            &mut progress,
        );
        let m = match measured {
            Ok(m) => m,
            Err(e) => return fail(record, e),
        };
        let (image, reference) = (&m.image, &m.image_reference);
        write_images(options, spec, &mut record, image, reference)?;
        if let Some(count) = record.calibrated_count {
            record.budget_missed =
                calibrate::missed(frame_ms, count, m.gpu_ms.unwrap_or(m.wall_ms));
        }
        record.gpu_ms = m.gpu_ms;
        record.pass_gpu_ms = m.pass_gpu_ms;
        record.wall_ms = Some(m.wall_ms);
        record.metrics = Some(m.metrics);
        record.scored = m.scored;
        record.reference_rel_mse = m.reference_rel_mse;
        record.image_mean_offset = Some(m.image_mean_offset).filter(|o| o.is_finite());
        record.image_mean_spread = m.image_mean_spread;
        record.flicker_frames = 0;
        record.lead_in = m.lead_in;
        (record.rel_mse_min, record.rel_mse_max) = m.rel_mse_range.unzip();
        record.nonfinite_estimates = m.nonfinite_estimates;
        record.stats = m.stats;
        record.sequence = Some(m.sequence);
        return Ok(record);
    }
    let measured = measure(
        ctx,
        renderers,
        &method,
        scene,
        gpu_scene,
        reference,
        suite.warmup,
        suite.repeats,
        suite.flicker_frames,
        progress,
    );
    let m = match measured {
        Ok(m) => m,
        Err(e) => return fail(record, e),
    };
    write_images(options, spec, &mut record, &m.image, reference)?;
    if let (Some(time_ms), Some(count)) = (spec.time_ms, record.calibrated_count) {
        record.budget_missed = calibrate::missed(time_ms, count, m.gpu_ms.unwrap_or(m.wall_ms));
    }
    record.gpu_ms = m.gpu_ms;
    record.pass_gpu_ms = m.pass_gpu_ms;
    record.wall_ms = Some(m.wall_ms);
    record.metrics = Some(m.metrics);
    record.scored = m.scored;
    record.reference_rel_mse = *reference_rel_mse;
    record.flicker = m.flicker;
    record.image_mean_offset = Some(m.image_mean_offset).filter(|o| o.is_finite());
    record.image_mean_spread = m.image_mean_spread;
    (record.rel_mse_min, record.rel_mse_max) = m.rel_mse_range.unzip();
    record.nonfinite_estimates = m.nonfinite_estimates;
    record.stats = m.stats;
    Ok(record)
}

/// Writes a run's thumbnail and error map (against `reference`) and names them in `record`.
fn write_images(
    options: &SuiteOptions,
    spec: &file::RunSpec,
    record: &mut RunRecord,
    image: &Image,
    reference: &Image,
) -> Result<()> {
    let factor = preview::factor_for(image.width, THUMBNAIL_WIDTH);
    let stem = spec.file_stem();
    let image_name = format!("images/{stem}.png");
    let error_name = format!("images/{stem}-error.png");
    image::png::write(
        &options.out.join(&image_name),
        &preview::downscale(image, factor),
        0.0,
    )?;
    let (w, h, data) = preview::error_map_rgb8(image, reference, factor);
    image::png::write_rgb8(&options.out.join(&error_name), w, h, &data)?;
    image::exr::write(&options.out.join(html::exr_of(&image_name)), image)?;
    record.image = Some(image_name);
    record.error_map = Some(error_name);
    Ok(())
}

/// The default output folder of a suite: `out/bench/<name>`, or `out/bench/<name>-shard-i-of-n`.
pub fn default_out(suite: &Suite, shard: Shard) -> PathBuf {
    let name = if shard == Shard::WHOLE {
        suite.name.clone()
    } else {
        format!("{}-shard-{}-of-{}", suite.name, shard.index, shard.count)
    };
    Path::new("out").join("bench").join(name)
}

/// The default reference cache: out/references.
pub fn default_cache() -> PathBuf {
    Path::new("out").join("references")
}
