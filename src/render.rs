//! One render from a loaded scene to files on disk (DESIGN.md "Outputs"): upload the scene,
//! run the chosen method, write `<out>.exr`, `<out>.png` and `<out>.json`, and score the image
//! against a reference when one is given. `irad render` is a thin shell over this.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use anyhow::{bail, Context as _, Result};
use serde_json::json;

use crate::gpu::{Context, PassTotals};
use crate::image::{self, exr, Image, Metrics, PassRecord, RenderRecord};
use crate::methods::gbuffer::PixelSampling;
use crate::methods::ir::schedule::Absorption;
use crate::methods::ir::{DirectLight, InstantRadiosity, IrSettings};
use crate::methods::reference::{Reference, ReferenceSettings};
use crate::scene::gpu::GpuScene;
use crate::scene::Scene;

#[derive(Clone, Debug)]
pub enum Method {
    Reference(ReferenceSettings),
    Ir(IrSettings),
}

impl Method {
    pub fn name(&self) -> &'static str {
        match self {
            Method::Reference(_) => "reference",
            Method::Ir(_) => "ir",
        }
    }

    pub fn seed(&self) -> u32 {
        match self {
            Method::Reference(s) => s.seed,
            Method::Ir(s) => s.seed,
        }
    }

    fn parameters(&self) -> BTreeMap<String, serde_json::Value> {
        let mut p = BTreeMap::new();
        match self {
            Method::Reference(s) => {
                p.insert("spp".into(), json!(s.spp));
                p.insert("max_depth".into(), json!(s.max_depth));
                p.insert("roulette_depth".into(), json!(s.roulette_depth));
                p.insert(
                    "pixel_centres".into(),
                    json!(s.pixels == PixelSampling::Centres),
                );
            }
            Method::Ir(s) => {
                p.insert("vpl_paths".into(), json!(s.paths));
                p.insert("frames".into(), json!(s.frames));
                p.insert(
                    "absorption".into(),
                    json!(match s.absorption {
                        Absorption::Fractional => "fractional",
                        Absorption::Roulette => "roulette",
                    }),
                );
                // The clamp is recorded only when on: it is a named, measured bias.
                if s.g_clamp > 0.0 {
                    p.insert("geometry_clamp".into(), json!(s.g_clamp));
                }
                p.insert("interleave".into(), json!(s.interleave));
                p.insert(
                    "pixel_centres".into(),
                    json!(s.pixels == PixelSampling::Centres),
                );
                p.insert(
                    "direct".into(),
                    json!(match s.direct {
                        DirectLight::NextEvent => "nee",
                        DirectLight::Vpl => "vpl",
                    }),
                );
            }
        }
        p
    }

    fn samples(&self) -> u64 {
        match self {
            Method::Reference(s) => s.spp as u64,
            Method::Ir(s) => s.frames as u64,
        }
    }
}

pub struct RenderJob<'a> {
    pub scene: &'a Scene,
    pub method: Method,
    /// Output stem: `<out>.exr`, `<out>.png`, `<out>.json`.
    pub out: PathBuf,
    /// PNG exposure in stops.
    pub exposure: f32,
    /// A reference EXR to score against.
    pub reference: Option<PathBuf>,
}

impl RenderJob<'_> {
    /// What the progress callback counts up to.
    pub fn method_samples(&self) -> u64 {
        self.method.samples()
    }
}

pub struct RenderReport {
    pub image: Image,
    pub record: RenderRecord,
    pub passes: PassTotals,
    pub paths: (PathBuf, PathBuf, PathBuf),
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
    Ok(reference)
}

/// Renders `job`, calling `progress(done, total)` as samples complete, and writes the outputs.
pub fn render(
    ctx: &Context,
    job: &RenderJob,
    progress: impl FnMut(u32, u32),
) -> Result<RenderReport> {
    let cam = &job.scene.camera;
    // Read the reference first: a bad path should not cost a whole render.
    let reference = job
        .reference
        .as_deref()
        .map(|p| read_reference(p, cam.width, cam.height))
        .transpose()?;
    let gpu_scene = GpuScene::upload(ctx, job.scene).context("uploading the scene")?;
    let mut warnings = job.scene.warnings.clone();
    let output = match &job.method {
        Method::Reference(settings) => {
            Reference::new(ctx)?.render(ctx, &gpu_scene, settings, progress)?
        }
        Method::Ir(settings) => {
            InstantRadiosity::new(ctx)?.render(ctx, job.scene, &gpu_scene, settings, progress)?
        }
    };
    if output.nonfinite_estimates > 0 {
        warnings.push(format!(
            "{} per-pixel estimates were NaN or Inf and were dropped (counted as black)",
            output.nonfinite_estimates
        ));
    }
    let metrics: Option<Metrics> = reference
        .as_ref()
        .map(|r| image::compare(&output.image, r))
        .transpose()?;
    let info = ctx.info();
    let record = RenderRecord {
        method: job.method.name().into(),
        parameters: job.method.parameters(),
        scene: scene_label(job.scene),
        scene_hash: format!("{:016x}", job.scene.content_hash),
        resolution: [cam.width, cam.height],
        seed: job.method.seed() as u64,
        samples: job.method.samples(),
        device: info.name.clone(),
        driver: info.driver.clone(),
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
        warnings,
        irad_version: image::sidecar::IRAD_VERSION.into(),
    };
    let paths = image::write_all(&job.out, &output.image, &record, job.exposure)?;
    Ok(RenderReport {
        image: output.image,
        record,
        passes: output.passes,
        paths,
    })
}
