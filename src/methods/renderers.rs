//! Each method's kernels, built on first use, so a benchmark that renders many times compiles
//! its pipelines once; the G-buffer and direct-light kernels are built once for every method.

use std::any::{Any, TypeId};
use std::cell::{OnceCell, RefCell};
use std::rc::Rc;

use thiserror::Error;

use crate::gpu::{Context, GpuError, GpuResult};
use crate::scene::gpu::GpuScene;
use crate::scene::Scene;

use super::across_frames::AnimationFrame;
use super::direct::GBufferAndDirectLight;
use super::interface::RenderMethod;
use super::{Method, RenderOutput};

/// The kernels of each method that has run, and the shared passes'.
#[derive(Default)]
pub struct Renderers {
    passes: OnceCell<GBufferAndDirectLight>,
    /// Each method's kernels by the method's type: an `Rc<M>` as `Rc<dyn Any>`.
    methods: RefCell<Vec<(TypeId, Rc<dyn Any>)>>,
}

#[derive(Debug, Error)]
pub enum RunError {
    /// The method does not render this scene's lights (lights.rs says why).
    #[error("{0}")]
    Declined(String),
    /// An animated scene given whole: a render shows one of its frames (`Scene::at_frame`).
    #[error("{0}")]
    Animated(String),
    #[error(transparent)]
    Gpu(#[from] GpuError),
}

impl Renderers {
    /// Renders `scene` (uploaded as `gpu_scene`) with `method`, calling `progress(done, total)`
    /// as samples complete. A method registered outside irad runs here too: the method value
    /// carries its entry.
    pub fn run(
        &self,
        ctx: &Context,
        method: &Method,
        scene: &Scene,
        gpu_scene: &GpuScene,
        progress: impl FnMut(u32, u32),
    ) -> Result<RenderOutput, RunError> {
        self.run_frame(
            ctx,
            method,
            scene,
            gpu_scene,
            &AnimationFrame::STILL,
            progress,
        )
    }

    /// `run` for one animation frame: `scene` is the frame's (`Scene::at_frame`), and the
    /// method gets `animation` (the frame, and the previous frame's scene where this
    /// `Renderers` rendered it just before; src/sequence.rs hands it).
    pub fn run_frame(
        &self,
        ctx: &Context,
        method: &Method,
        scene: &Scene,
        gpu_scene: &GpuScene,
        animation: &AnimationFrame<'_>,
        mut progress: impl FnMut(u32, u32),
    ) -> Result<RenderOutput, RunError> {
        // Refused before any kernel is built.
        if let Some(why) = method.declines(scene) {
            return Err(RunError::Declined(why));
        }
        method
            .fits(scene, ctx.info().max_storage_buffer_range)
            .map_err(|e| RunError::Gpu(GpuError::DoesNotFit(e)))?;
        method.entry().run(
            self,
            ctx,
            method.settings_any(),
            scene,
            gpu_scene,
            animation,
            &mut progress,
        )
    }

    /// The shared passes' kernels and `M`'s, built the first time `M` runs.
    pub(crate) fn kernels<M: RenderMethod>(
        &self,
        ctx: &Context,
    ) -> GpuResult<(&GBufferAndDirectLight, Rc<M>)> {
        let passes = match self.passes.get() {
            Some(p) => p,
            None => {
                let p = GBufferAndDirectLight::new(ctx)?;
                self.passes.get_or_init(|| p)
            }
        };
        let id = TypeId::of::<M>();
        if let Some((_, m)) = self.methods.borrow().iter().find(|(t, _)| *t == id) {
            let m = m.clone().downcast::<M>().expect("kept by its TypeId");
            return Ok((passes, m));
        }
        let m = Rc::new(M::new(ctx)?);
        self.methods.borrow_mut().push((id, m.clone()));
        Ok((passes, m))
    }
}
