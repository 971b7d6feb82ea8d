//! A kernel specialized to each scene it runs on: scene.glsl's SCENE_HAS_* specialization
//! constants (0-2) set from the scene's features, and optionally one more boolean of the
//! kernel's own (constant 3), built the first time a combination is recorded. gallivm
//! (lavapipe) runs the code of every branch, taken or not, so code for what a scene lacks costs
//! its full time unless it is compiled out (scene.glsl has the measurements).

use std::cell::OnceCell;

use crate::gpu::{Context, GpuResult, Kernel};
use crate::scene::gpu::SceneFeatures;

pub struct SceneKernel {
    ctx: Context,
    name: &'static str,
    /// By SceneFeatures::index, plus 8 when the kernel's own constant is set.
    variants: [OnceCell<Kernel>; 16],
}

impl SceneKernel {
    /// Builds nothing yet, but checks that the kernel is embedded and its layout reflects.
    pub fn new(ctx: &Context, name: &'static str) -> GpuResult<Self> {
        Kernel::check_embedded(name)?;
        Ok(SceneKernel {
            ctx: ctx.clone(),
            name,
            variants: Default::default(),
        })
    }

    /// The kernel for a scene with `features` (for kernels without a constant 3 of their own:
    /// it takes the module's default, and shares its slot with `get_with(features, false)`).
    pub fn get(&self, features: SceneFeatures) -> GpuResult<&Kernel> {
        self.build(features, None)
    }

    /// The kernel for a scene with `features`, its constant 3 set to `flag`.
    pub fn get_with(&self, features: SceneFeatures, flag: bool) -> GpuResult<&Kernel> {
        self.build(features, Some(flag))
    }

    fn build(&self, features: SceneFeatures, flag: Option<bool>) -> GpuResult<&Kernel> {
        let cell = &self.variants[features.index() + 8 * usize::from(flag == Some(true))];
        if let Some(kernel) = cell.get() {
            return Ok(kernel);
        }
        let mut constants = features.constants().to_vec();
        constants.extend(flag.map(u32::from));
        let _ = cell.set(Kernel::specialized(&self.ctx, self.name, &constants)?);
        Ok(cell.get().expect("set above"))
    }
}
