//! Each method's kernels, built on first use, so a benchmark that renders many times compiles
//! its pipelines once.

use std::cell::OnceCell;

use thiserror::Error;

use crate::gpu::{Context, GpuError};
use crate::methods::bir::{Bir, BirError};
use crate::methods::bundles::{Bundles, BundlesError};
use crate::methods::envmap::{Env, EnvError};
use crate::methods::ir::{InstantRadiosity, IrError};
use crate::methods::lightfield::{Lightfield, LightfieldError};
use crate::methods::reference::Reference;
use crate::methods::{device_fit, Method, RenderOutput};
use crate::scene::gpu::GpuScene;
use crate::scene::Scene;

/// Each method's kernels, built the first time the method runs.
#[derive(Default)]
pub struct Renderers {
    reference: OnceCell<Reference>,
    ir: OnceCell<InstantRadiosity>,
    bir: OnceCell<Bir>,
    bundles: OnceCell<Bundles>,
    env: OnceCell<Env>,
    lightfield: OnceCell<Lightfield>,
}

#[derive(Debug, Error)]
pub enum RunError {
    #[error("{0}")]
    Declined(String),
    #[error(transparent)]
    Gpu(#[from] GpuError),
}

impl Renderers {
    /// Renders `scene` (uploaded as `gpu_scene`) with `method`, calling `progress(done, total)`
    /// as samples complete.
    pub fn run(
        &self,
        ctx: &Context,
        method: &Method,
        scene: &Scene,
        gpu_scene: &GpuScene,
        progress: impl FnMut(u32, u32),
    ) -> Result<RenderOutput, RunError> {
        if let Some(why) = method.declines(scene) {
            return Err(RunError::Declined(why));
        }
        device_fit::check_method(method, scene, ctx.info().max_storage_buffer_range)
            .map_err(|e| RunError::Gpu(GpuError::DoesNotFit(e)))?;
        // A cut traversal left over from an earlier render (one that failed before its
        // check) is not this render's; the methods' frames check it (progressive::run).
        gpu_scene.bvh.clear_loop_cuts()?;
        match method {
            Method::Reference(settings) => {
                let r = get_or_try_init(&self.reference, || Reference::new(ctx))?;
                Ok(r.render(ctx, gpu_scene, settings, progress)?)
            }
            Method::Ir(settings) => {
                let ir = get_or_try_init(&self.ir, || InstantRadiosity::new(ctx))?;
                ir.render(ctx, scene, gpu_scene, settings, progress)
                    .map_err(|e| match e {
                        IrError::Environment => RunError::Declined(e.to_string()),
                        IrError::Gpu(g) => RunError::Gpu(g),
                    })
            }
            Method::Bir(settings) => {
                let bir = get_or_try_init(&self.bir, || Bir::new(ctx))?;
                bir.render(ctx, scene, gpu_scene, settings, progress)
                    .map_err(|e| match e {
                        BirError::Environment => RunError::Declined(e.to_string()),
                        BirError::Gpu(g) => RunError::Gpu(g),
                    })
            }
            Method::Bundles(settings) => {
                let bundles = get_or_try_init(&self.bundles, || Bundles::new(ctx))?;
                bundles
                    .render(ctx, scene, gpu_scene, settings, progress)
                    .map_err(|e| match e {
                        BundlesError::Gpu(g) => RunError::Gpu(g),
                        e => RunError::Declined(e.to_string()),
                    })
            }
            Method::Env(settings) => {
                let env = get_or_try_init(&self.env, || Env::new(ctx))?;
                env.render(ctx, scene, gpu_scene, settings, progress)
                    .map_err(|e| match e {
                        EnvError::Gpu(g) => RunError::Gpu(g),
                        e => RunError::Declined(e.to_string()),
                    })
            }
            Method::Lightfield(settings) => {
                let lf = get_or_try_init(&self.lightfield, || Lightfield::new(ctx))?;
                lf.render(ctx, scene, gpu_scene, settings, progress)
                    .map_err(|e| match e {
                        LightfieldError::Gpu(g) => RunError::Gpu(g),
                        e => RunError::Declined(e.to_string()),
                    })
            }
        }
    }
}

/// `OnceCell::get_or_try_init` is not stable yet.
fn get_or_try_init<T>(
    cell: &OnceCell<T>,
    init: impl FnOnce() -> Result<T, GpuError>,
) -> Result<&T, GpuError> {
    if let Some(v) = cell.get() {
        return Ok(v);
    }
    let v = init()?;
    Ok(cell.get_or_init(|| v))
}
