//! One render from a loaded scene to files on disk (docs/DESIGN.md "Outputs"): check everything
//! that can fail without the GPU, upload the scene, run the chosen method, score the image
//! against a reference when one is given, and write `<out>.exr`, `<out>.png`, any maps and
//! `<out>.json` as one set (`image::write_all`). `irad render` is a thin shell over this.

use std::path::{Path, PathBuf};

use anyhow::{bail, Context as _, Result};

use crate::gpu::{Context, PassTotals};
use crate::image::{self, exr, Image, Metrics, OutputFiles, PassRecord, RenderRecord};
use crate::methods::{AnimationFrame, Method, Renderers};
use crate::scene::gpu::GpuScene;
use crate::scene::Scene;

pub struct RenderJob<'a> {
    pub scene: &'a Scene,
    pub method: Method,
    /// Output stem: `<out>.exr`, `<out>.png`, `<out>.json`; a folder gets `<out>/render.*`
    /// (`image::sidecar::output_stem`).
    pub out: PathBuf,
    /// PNG exposure in stops.
    pub exposure: f32,
    /// A reference EXR to score against.
    pub reference: Option<PathBuf>,
    /// The animation frame `scene` shows (`Scene::at_frame`), for the record.
    pub frame: Option<u32>,
}

impl RenderJob<'_> {
    /// What the progress callback counts up to.
    pub fn method_samples(&self) -> u64 {
        self.method.samples()
    }

    /// Every check that can fail without the GPU, so that a bad value costs no render and
    /// leaves the previous outputs as they were: the exposure is finite, the output folder is
    /// created and writable with no folder in an output's place, and the reference reads, is
    /// finite and has the render's size.
    pub fn check(&self) -> Result<Checked> {
        if !self.exposure.is_finite() {
            bail!(
                "--exposure must be a finite number of stops, got {}",
                self.exposure
            );
        }
        let files = image::sidecar::check_writable(&self.out)?;
        let cam = &self.scene.camera;
        let reference = self
            .reference
            .as_deref()
            .map(|p| read_reference(p, cam.width, cam.height))
            .transpose()?;
        Ok(Checked { reference, files })
    }
}

/// What `RenderJob::check` found: the reference image, read, and where the outputs go.
pub struct Checked {
    reference: Option<Image>,
    pub files: OutputFiles,
}

pub struct RenderReport {
    pub image: Image,
    pub record: RenderRecord,
    pub passes: PassTotals,
    pub files: OutputFiles,
}

/// The scene's name in records: its path, or `embedded:<name>`.
pub fn scene_label(scene: &Scene) -> String {
    match &scene.source {
        Some(path) => path.display().to_string(),
        None => format!("embedded:{}", scene.name),
    }
}

fn read_reference(path: &Path, width: u32, height: u32) -> Result<Image> {
    let reference = exr::read(path)?;
    if (reference.width, reference.height) != (width, height) {
        bail!(
            "reference {} is {}x{}, the render is {width}x{height}",
            path.display(),
            reference.width,
            reference.height
        );
    }
    let bad = reference
        .pixels
        .iter()
        .flatten()
        .filter(|v| !v.is_finite())
        .count();
    if bad > 0 {
        bail!(
            "reference {} has {bad} NaN or infinite values; a reference must be finite",
            path.display()
        );
    }
    Ok(reference)
}

/// Renders `job`, calling `progress(done, total)` as samples complete, and writes the outputs.
pub fn render(
    ctx: &Context,
    job: &RenderJob,
    progress: impl FnMut(u32, u32),
) -> Result<RenderReport> {
    let checked = job.check()?;
    render_checked(ctx, job, checked, progress)
}

/// `render` for a job already checked (`RenderJob::check`, which `irad render` calls before it
/// opens the device).
pub fn render_checked(
    ctx: &Context,
    job: &RenderJob,
    checked: Checked,
    progress: impl FnMut(u32, u32),
) -> Result<RenderReport> {
    let animation = AnimationFrame::alone(job.frame.unwrap_or(0));
    render_checked_with(
        ctx,
        &Renderers::default(),
        job,
        checked,
        &animation,
        progress,
    )
}

/// `render_checked` with kernels built once for many renders (a sequence's frames), handing
/// the method `animation` (the frame and the one rendered before it).
pub fn render_checked_with(
    ctx: &Context,
    renderers: &Renderers,
    job: &RenderJob,
    checked: Checked,
    animation: &AnimationFrame<'_>,
    progress: impl FnMut(u32, u32),
) -> Result<RenderReport> {
    let cam = &job.scene.camera;
    let reference = checked.reference;
    let gpu_scene = GpuScene::upload(ctx, job.scene).context("uploading the scene")?;
    let mut warnings = job.scene.warnings.clone();
    let maps = gpu_scene.environment_frames() as u64;
    let frames = job.method.samples();
    if maps > 1 && frames % maps != 0 {
        warnings.push(format!(
            "the environment is a sequence of {maps} maps (frame f shows map f mod {maps}) and this render has {frames} frames, not a multiple of {maps}: the maps are not weighed equally, so the image is not the sequence's average"
        ));
    }
    for (k, l) in job.scene.luminaires.iter().enumerate() {
        let atlases = l.luminaire.sequence.len() as u64;
        if atlases > 1 && frames % atlases != 0 {
            warnings.push(format!(
                "luminaire {k} ({}) is a sequence of {atlases} atlases (frame f shows atlas f mod {atlases}) and this render has {frames} frames, not a multiple of {atlases}: the atlases are not weighed equally",
                l.luminaire.source.display()
            ));
        }
    }
    let output =
        renderers.run_frame(ctx, &job.method, job.scene, &gpu_scene, animation, progress)?;
    if output.nonfinite_estimates > 0 {
        warnings.push(format!(
            "{} per-pixel estimates were NaN or Inf and were dropped (counted as black)",
            output.nonfinite_estimates
        ));
    }
    // The scene's warnings were logged when it loaded; the render's own are logged here.
    for w in &warnings[job.scene.warnings.len()..] {
        log::warn!("{w}");
    }
    let metrics: Option<Metrics> = reference
        .as_ref()
        .map(|r| image::compare(&output.image, r))
        .transpose()?;
    let info = ctx.info();
    let names: Vec<&str> = output.maps.iter().map(|(n, _)| n.as_str()).collect();
    let record = RenderRecord {
        method: job.method.name().into(),
        parameters: job.method.parameters(),
        scene: scene_label(job.scene),
        scene_path: job.scene.source.as_deref().map(image::sidecar::absolute),
        scene_hash: format!("{:016x}", job.scene.content_hash),
        resolution: [cam.width, cam.height],
        seed: job.method.seed() as u64,
        frame: job.frame,
        samples: job.method.samples(),
        device: info.name.clone(),
        driver: info.driver.clone(),
        staging: ctx.force_staging().then(|| "forced".to_string()),
        passes: output
            .passes
            .passes
            .iter()
            .map(|(name, gpu_ms, count)| PassRecord {
                name: name.clone(),
                gpu_ms: *gpu_ms,
                count: *count,
            })
            .collect(),
        gpu_ms_total: output.passes.total_gpu_ms(),
        wall_ms: output.wall_ms,
        metrics,
        reference: job.reference.as_deref().map(image::sidecar::absolute),
        warnings,
        stats: output.stats.iter().cloned().collect(),
        files: OutputFiles::new(&job.out, &names).names(),
        irad_version: image::sidecar::IRAD_VERSION.into(),
        git_commit: image::sidecar::GIT_COMMIT.into(),
        load: Some(image::sidecar::LoadTimes {
            parse_ms: job.scene.load_ms,
            triangle_bvh_ms: gpu_scene.build_ms.triangle_bvh,
            light_bvh_ms: gpu_scene.build_ms.light_bvh,
            upload_ms: gpu_scene.build_ms.upload,
        }),
    };
    let files = image::write_all(&job.out, &output.image, &record, job.exposure, &output.maps)?;
    Ok(RenderReport {
        image: output.image,
        record,
        passes: output.passes,
        files,
    })
}
