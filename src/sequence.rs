//! Sequences (docs/DESIGN.md "Animation"): every frame of an animated scene rendered as its own
//! image from the method's count of samples, each frame independent of the others (the
//! baseline without reuse across frames). `render_frames` hands each frame's image to a
//! callback; `render_sequence` writes `OUT/frame_NNNN.{exr,png,json}` per frame (one set, the
//! JSON last, as `irad render` writes), `OUT/sequence.json` after every frame, and a preview,
//! and resumes an interrupted sequence from the frames it finds complete.
//!
//! Frame f renders the still scene `Scene::at_frame(f)` with the method's seed plus f
//! (`frame_seed`), so its noise differs from the next frame's, and `irad render --frame f` with
//! the same seed gives the same bits.

use std::collections::BTreeMap;
use std::ops::Range;
use std::path::{Path, PathBuf};

use anyhow::{bail, Context as _, Result};
use serde::{Deserialize, Serialize};

use crate::gpu::Context;
use crate::image::{self, exr, Metrics, RenderRecord, SequenceMetrics};
use crate::lock::HolderLock;
use crate::methods::{AnimationFrame, Changes, Method, PreviousFrame, RenderOutput, Renderers};
use crate::render::{self, RenderJob, RenderReport};
use crate::scene::gpu::GpuScene;
use crate::scene::Scene;

/// The seed animation frame `frame` renders with.
pub fn frame_seed(seed: u32, frame: u32) -> u32 {
    seed.wrapping_add(frame)
}

/// `method` as animation frame `frame` runs it (its seed, `frame_seed`).
pub fn frame_method(method: &Method, frame: u32) -> Method {
    method.with_seed(frame_seed(method.seed(), frame))
}

/// Renders each frame of `frames` of `scene` with `method` (its count per frame), calling
/// `on_frame(frame, the frame's scene, its output)` after each. Nothing is written.
pub fn render_frames(
    ctx: &Context,
    scene: &Scene,
    method: &Method,
    frames: Range<u32>,
    on_frame: impl FnMut(u32, &Scene, RenderOutput) -> Result<()>,
) -> Result<()> {
    render_frames_with(ctx, &Renderers::default(), scene, method, frames, on_frame)
}

/// `render_frames` with kernels already built (a suite's, warmed by earlier renders).
pub fn render_frames_with(
    ctx: &Context,
    renderers: &Renderers,
    scene: &Scene,
    method: &Method,
    frames: Range<u32>,
    mut on_frame: impl FnMut(u32, &Scene, RenderOutput) -> Result<()>,
) -> Result<()> {
    // Only a method that carries state across frames gets the previous frame (a second scene
    // in memory and a comparison of the two each frame).
    let carries = !method.across_frames().carries_nothing();
    let mut previous: Option<(u32, Scene)> = None;
    for f in frames {
        let still = scene.at_frame(f)?;
        // Geometry does not move, but the lights, emission and map that the upload's tables
        // are built from do: the frame's scene is uploaded whole.
        let gpu = GpuScene::upload(ctx, &still).context("uploading the scene")?;
        let animation = animation_frame(f, previous.as_ref(), &still);
        let output = renderers.run_frame(
            ctx,
            &frame_method(method, f),
            &still,
            &gpu,
            &animation,
            |_, _| {},
        )?;
        on_frame(f, &still, output)?;
        previous = carries.then_some((f, still));
    }
    Ok(())
}

/// What the driver hands a method rendering frame `f` (`still`): the frame rendered just
/// before with the same kernels, where it is `f`'s predecessor, and what changed since.
fn animation_frame<'a>(
    f: u32,
    previous: Option<&'a (u32, Scene)>,
    still: &Scene,
) -> AnimationFrame<'a> {
    AnimationFrame {
        frame: f,
        previous: previous
            .filter(|(p, _)| p.checked_add(1) == Some(f))
            .map(|(p, scene)| PreviousFrame {
                frame: *p,
                scene,
                changed: Changes::between(scene, still),
            }),
    }
}

/// A sequence to render into a folder.
pub struct SequenceJob<'a> {
    /// An animated scene.
    pub scene: &'a Scene,
    /// The method, its count the samples of each frame.
    pub method: Method,
    pub frames: Range<u32>,
    pub out: PathBuf,
    pub exposure: f32,
    /// A folder of the same animation's reference frames (an earlier sequence, its
    /// frame_NNNN.exr): each frame is scored against its own, and the sequence as a whole.
    pub reference: Option<PathBuf>,
    /// With a reference: HDR-FLIP per frame too (src/image/flip.rs; about 40 ms a frame at
    /// 128x96 in release).
    pub flip: bool,
}

/// OUT/sequence.json: what was rendered, once, and each frame's record in brief.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SequenceRecord {
    pub scene: String,
    pub scene_hash: String,
    /// [width, height] of every frame ([0, 0] in records written before it was recorded).
    #[serde(default)]
    pub resolution: [u32; 2],
    pub method: String,
    /// The method's settings but the seed (each frame's is `seed` + its frame).
    pub parameters: BTreeMap<String, serde_json::Value>,
    pub seed: u32,
    /// What the method keeps from one frame to the next with its settings
    /// (`RenderMethod::across_frames`).
    #[serde(default)]
    pub across_frames: String,
    /// The animation's frame count and rate; `frames` the range rendered.
    pub animation_frames: u32,
    pub fps: f32,
    pub frames: [u32; 2],
    pub device: String,
    pub driver: String,
    pub irad_version: String,
    /// The commit irad was built from (`RenderRecord::git_commit`).
    #[serde(default)]
    pub git_commit: String,
    /// The scene file's absolute path (`RenderRecord::scene_path`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub scene_path: Option<String>,
    /// The PNGs' exposure in stops.
    pub exposure: f32,
    /// Each complete frame, in order.
    pub rendered: Vec<FrameSummary>,
    /// Against the reference frames, when given: the mean over frames, the worst frame and
    /// the flicker (docs/DESIGN.md "Error metrics").
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub reference: Option<String>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub metrics: Option<SequenceMetrics>,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct FrameSummary {
    pub frame: u32,
    pub seed: u32,
    pub passes: Vec<image::PassRecord>,
    pub gpu_ms_total: Option<f64>,
    pub wall_ms: f64,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub metrics: Option<Metrics>,
    #[serde(default)]
    pub warnings: Vec<String>,
    pub files: Vec<String>,
}

impl FrameSummary {
    fn of(record: &RenderRecord) -> FrameSummary {
        FrameSummary {
            frame: record.frame.unwrap_or(0),
            seed: record.seed as u32,
            passes: record.passes.clone(),
            gpu_ms_total: record.gpu_ms_total,
            wall_ms: record.wall_ms,
            metrics: record.metrics,
            warnings: record.warnings.clone(),
            files: record.files.clone(),
        }
    }
}

/// Frame `f`'s output stem in `out`.
pub fn frame_stem(out: &Path, f: u32) -> PathBuf {
    out.join(format!("frame_{f:04}"))
}

/// What `render_sequence` did.
pub struct SequenceReport {
    pub record: SequenceRecord,
    /// Frames found complete from an earlier run and kept.
    pub resumed: Vec<u32>,
    /// The preview files written (an animated PNG, an MP4 where ffmpeg is installed).
    pub previews: Vec<PathBuf>,
    pub warnings: Vec<String>,
}

/// Where a sequence stands, for a progress bar: frames, and the samples of the frame under way.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SequenceProgress {
    pub frames_done: u32,
    pub frames: u32,
    /// The frame under way (the range's end once all are done).
    pub frame: u32,
    /// The method's count done of the frame under way, of `samples`.
    pub samples_done: u32,
    pub samples: u32,
}

/// Renders `job` into its folder, resuming from the frames an earlier run of the same
/// sequence completed; `progress` before each frame, as its samples complete and at the end,
/// and `on_frame` after each frame (the frame's report: image and record).
pub fn render_sequence(
    ctx: &Context,
    job: &SequenceJob,
    mut progress: impl FnMut(SequenceProgress),
    mut on_frame: impl FnMut(u32, &RenderReport),
) -> Result<SequenceReport> {
    let Some(animation) = &job.scene.animation else {
        bail!(
            "{} has no [animation]: a sequence renders an animated scene's frames",
            render::scene_label(job.scene)
        );
    };
    if job.frames.is_empty() || job.frames.end > animation.frames {
        bail!(
            "frames {}..{} are not within the animation's 0..{}",
            job.frames.start,
            job.frames.end,
            animation.frames
        );
    }
    std::fs::create_dir_all(&job.out)
        .with_context(|| format!("creating the output folder {}", job.out.display()))?;
    let acquired = HolderLock::acquire(&job.out)?;
    let _lock = acquired.lock;
    let mut warnings: Vec<String> = acquired
        .stale
        .into_iter()
        .map(|holder| format!("took over {}'s lock of a sequence that stopped", holder))
        .collect();
    let info = ctx.info();
    let mut record = SequenceRecord {
        scene: render::scene_label(job.scene),
        scene_hash: format!("{:016x}", job.scene.content_hash),
        resolution: [job.scene.camera.width, job.scene.camera.height],
        method: job.method.name().into(),
        parameters: job.method.parameters(),
        seed: job.method.seed(),
        across_frames: job.method.across_frames().describe(),
        animation_frames: animation.frames,
        fps: animation.fps,
        frames: [job.frames.start, job.frames.end],
        device: info.name.clone(),
        driver: info.driver.clone(),
        irad_version: image::sidecar::IRAD_VERSION.into(),
        git_commit: image::sidecar::GIT_COMMIT.into(),
        scene_path: job.scene.source.as_deref().map(image::sidecar::absolute),
        exposure: job.exposure,
        rendered: vec![],
        reference: job.reference.as_deref().map(image::sidecar::absolute),
        metrics: None,
    };
    if let Some(dir) = &job.reference {
        check_reference_sequence(dir, &record, job.frames.clone())?;
    }
    let record_path = job.out.join("sequence.json");
    if record_path.exists() {
        let earlier: SequenceRecord = read_json(&record_path)?;
        if let Some(what) = differs(&earlier, &record) {
            bail!(
                "{} holds frames of another sequence ({what}): choose another output folder, or \
                 remove it to replace them",
                job.out.display()
            );
        }
        // Frames an earlier run rendered outside this range stay listed.
        record.rendered = earlier
            .rendered
            .into_iter()
            .filter(|r| !job.frames.contains(&r.frame))
            .collect();
    }
    let renderers = Renderers::default();
    let total = job.frames.len() as u32;
    let mut resumed = vec![];
    // The frame rendered just before, for a method that carries state across frames; a frame
    // kept from an earlier run leaves none.
    let mut previous: Option<(u32, Scene)> = None;
    let carries = job.method.across_frames();
    for (done, f) in job.frames.clone().enumerate() {
        let at = |samples_done, samples| SequenceProgress {
            frames_done: done as u32,
            frames: total,
            frame: f,
            samples_done,
            samples,
        };
        progress(at(0, job.method.samples().min(u32::MAX as u64) as u32));
        let method = frame_method(&job.method, f);
        let stem = frame_stem(&job.out, f);
        let reference = job
            .reference
            .as_ref()
            .map(|dir| frame_stem(dir, f).with_extension("exr"));
        if let Some(earlier) = complete_frame(&stem, job.scene, &method, f)? {
            record.rendered.push(FrameSummary::of(&earlier));
            record.rendered.sort_by_key(|r| r.frame);
            resumed.push(f);
            previous = None;
            continue;
        }
        let still = job.scene.at_frame(f)?;
        let after_kept = resumed.last() == Some(&(f.wrapping_sub(1)));
        let first_after_zero = f == job.frames.start && f > 0;
        if !carries.carries_nothing() && previous.is_none() && (after_kept || first_after_zero) {
            let why = match after_kept {
                true => "the first rendered after frames kept from an earlier run",
                false => "the first of a range that starts after frame 0",
            };
            warnings.push(format!(
                "{} carries state across frames ({}); frame {f}, {why}, starts without it, so \
                 frames from {f} on may differ from a sequence rendered straight through from 0",
                job.method.name(),
                carries.describe()
            ));
        }
        let frame_job = RenderJob {
            scene: &still,
            method,
            out: stem,
            exposure: job.exposure,
            reference,
            frame: Some(f),
        };
        let checked = frame_job.check()?;
        let animation = animation_frame(f, previous.as_ref(), &still);
        let report = render::render_checked_with(
            ctx,
            &renderers,
            &frame_job,
            checked,
            &animation,
            |d, t| progress(at(d, t)),
        )
        .with_context(|| format!("rendering animation frame {f}"))?;
        on_frame(f, &report);
        record.rendered.push(FrameSummary::of(&report.record));
        record.rendered.sort_by_key(|r| r.frame);
        write_json(&record_path, &record)?;
        previous = (!carries.carries_nothing()).then_some((f, still));
    }
    progress(SequenceProgress {
        frames_done: total,
        frames: total,
        frame: job.frames.end,
        samples_done: 0,
        samples: 0,
    });
    if let Some(dir) = &job.reference {
        // Frame by frame (two in memory), kept frames included: their records may predate the
        // reference.
        let read = |d: &Path, f: u32| exr::read(&frame_stem(d, f).with_extension("exr"));
        let mut score = match job.flip {
            true => image::SequenceScore::with_flip(image::flip::DEFAULT_PIXELS_PER_DEGREE),
            false => image::SequenceScore::default(),
        };
        for summary in record.rendered.iter_mut() {
            if job.frames.contains(&summary.frame) {
                let f = summary.frame;
                summary.metrics = Some(score.push(read(&job.out, f)?, read(dir, f)?)?);
            }
        }
        let (_, mut summary) = score.finish();
        summary.worst_frame += job.frames.start as usize;
        record.metrics = Some(summary);
    }
    write_json(&record_path, &record)?;
    let (previews, preview_warnings) =
        previews(&job.out, job.frames.clone(), animation.fps, job.exposure)?;
    warnings.extend(preview_warnings);
    Ok(SequenceReport {
        record,
        resumed,
        previews,
        warnings,
    })
}

/// A reference folder's frames must exist for `frames`; where it has a sequence.json, it must
/// be of the same scene and cover them.
fn check_reference_sequence(dir: &Path, now: &SequenceRecord, frames: Range<u32>) -> Result<()> {
    let record_path = dir.join("sequence.json");
    if record_path.exists() {
        let reference: SequenceRecord = read_json(&record_path)?;
        if reference.scene_hash != now.scene_hash {
            bail!(
                "the reference sequence {} is of another scene or another version of it (hash {}, \
                 this one {})",
                dir.display(),
                reference.scene_hash,
                now.scene_hash
            );
        }
    }
    if let Some(f) = frames
        .clone()
        .find(|&f| !frame_stem(dir, f).with_extension("exr").exists())
    {
        bail!(
            "the reference sequence {} has no frame {f} ({}): render frames {}..{} there first",
            dir.display(),
            frame_stem(dir, f).with_extension("exr").display(),
            frames.start,
            frames.end
        );
    }
    Ok(())
}

/// What makes `earlier` another sequence than `now`, in words; None when it is the same one.
fn differs(earlier: &SequenceRecord, now: &SequenceRecord) -> Option<String> {
    // `--resolution` changes the frames' size, not the scene's hash.
    if earlier.resolution != [0, 0] && earlier.resolution != now.resolution {
        return Some(format!(
            "its frames are {}x{}, now {}x{}",
            earlier.resolution[0], earlier.resolution[1], now.resolution[0], now.resolution[1]
        ));
    }
    if earlier.scene_hash != now.scene_hash {
        return Some(format!(
            "the scene {} has other contents (hash {}, now {})",
            now.scene, earlier.scene_hash, now.scene_hash
        ));
    }
    if earlier.method != now.method {
        return Some(format!("method {}, now {}", earlier.method, now.method));
    }
    // Frames rendered with and without reuse across frames are not one sequence (an empty
    // value: a record from before it was written down).
    if !earlier.across_frames.is_empty() && earlier.across_frames != now.across_frames {
        return Some(format!(
            "what {} keeps across frames: {}, now {}",
            now.method, earlier.across_frames, now.across_frames
        ));
    }
    if earlier.seed != now.seed {
        return Some(format!("seed {}, now {}", earlier.seed, now.seed));
    }
    if earlier.exposure != now.exposure {
        return Some(format!(
            "exposure {}, now {}",
            earlier.exposure, now.exposure
        ));
    }
    if earlier.parameters != now.parameters {
        let keys: std::collections::BTreeSet<&String> = earlier
            .parameters
            .keys()
            .chain(now.parameters.keys())
            .collect();
        let changed: Vec<String> = keys
            .into_iter()
            .filter(|k| earlier.parameters.get(*k) != now.parameters.get(*k))
            .map(|k| {
                let show = |v: Option<&serde_json::Value>| {
                    v.map_or("unset".to_string(), |v| v.to_string())
                };
                format!(
                    "{k} {}, now {}",
                    show(earlier.parameters.get(k)),
                    show(now.parameters.get(k))
                )
            })
            .collect();
        return Some(changed.join(", "));
    }
    None
}

/// Frame `f`'s record at `stem` when an earlier run completed it with this method, scene and
/// seed (its JSON, written last, is there); None when the frame is still to render. A frame of
/// another render is an error rather than overwritten.
fn complete_frame(
    stem: &Path,
    scene: &Scene,
    method: &Method,
    f: u32,
) -> Result<Option<RenderRecord>> {
    let json = stem.with_extension("json");
    if !json.exists() {
        return Ok(None);
    }
    let record = RenderRecord::read(&json)?;
    let same = record.method == method.name()
        && record.parameters == method.parameters()
        && record.seed == method.seed() as u64
        && record.scene_hash == format!("{:016x}", scene.content_hash)
        && record.resolution == [scene.camera.width, scene.camera.height]
        && record.frame == Some(f);
    if !same {
        bail!(
            "{} is a render of another sequence (method {}, seed {}, frame {:?}, {}x{}): remove \
             it or choose another output folder",
            json.display(),
            record.method,
            record.seed,
            record.frame,
            record.resolution[0],
            record.resolution[1]
        );
    }
    let missing = record
        .files
        .iter()
        .map(|name| json.with_file_name(name))
        .find(|p| !p.exists());
    Ok(match missing {
        // An image removed by hand: the frame is rendered again.
        Some(_) => None,
        None => Some(record),
    })
}

/// An animated PNG of the frames' tone-mapped images at the animation's rate, and an MP4 where
/// ffmpeg is installed (its failure only warns).
fn previews(
    out: &Path,
    frames: Range<u32>,
    fps: f32,
    exposure: f32,
) -> Result<(Vec<PathBuf>, Vec<String>)> {
    let apng = out.join("preview.png");
    let first = frames.start;
    image::png::write_animated(
        &apng,
        frames.len(),
        |i| exr::read(&frame_stem(out, first + i as u32).with_extension("exr")),
        fps,
        exposure,
    )?;
    let mut written = vec![apng];
    let mut warnings = vec![];
    let ffmpeg_found = std::env::var_os("PATH")
        .is_some_and(|paths| std::env::split_paths(&paths).any(|p| p.join("ffmpeg").is_file()));
    if ffmpeg_found {
        let mp4 = out.join("preview.mp4");
        let status = std::process::Command::new("ffmpeg")
            .args(["-y", "-loglevel", "error", "-framerate"])
            .arg(fps.to_string())
            .arg("-start_number")
            .arg(frames.start.to_string())
            .arg("-i")
            .arg(out.join("frame_%04d.png"))
            .args([
                "-frames:v",
                &frames.len().to_string(),
                "-vf",
                "scale=trunc(iw/2)*2:trunc(ih/2)*2",
                "-pix_fmt",
                "yuv420p",
            ])
            .arg(&mp4)
            .status();
        match status {
            Ok(s) if s.success() => written.push(mp4),
            Ok(s) => warnings.push(format!("ffmpeg exited with {s}: no preview.mp4")),
            Err(e) => warnings.push(format!("ffmpeg did not run ({e}): no preview.mp4")),
        }
    }
    Ok((written, warnings))
}

fn read_json<T: for<'de> Deserialize<'de>>(path: &Path) -> Result<T> {
    let text =
        std::fs::read_to_string(path).with_context(|| format!("reading {}", path.display()))?;
    serde_json::from_str(&text)
        .with_context(|| format!("{}: not a sequence record", path.display()))
}

/// Written under a temporary name and renamed, so a reader never sees half a record.
fn write_json<T: Serialize>(path: &Path, value: &T) -> Result<()> {
    let tmp = path.with_extension("json.tmp");
    let text = serde_json::to_string_pretty(value)?;
    std::fs::write(&tmp, text + "\n").with_context(|| format!("writing {}", tmp.display()))?;
    std::fs::rename(&tmp, path).with_context(|| format!("writing {}", path.display()))
}
