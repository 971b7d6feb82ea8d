//! A kernel specialized to each scene it runs on: scene.glsl's SCENE_HAS_* specialization
//! constants (0-2) set from the scene's features, and optionally one more boolean of the
//! kernel's own (constant 3), or two (constants 3 and 4), built the first time a combination is
//! recorded. gallivm
//! (lavapipe) runs the code of every branch, taken or not, so code for what a scene lacks costs
//! its full time unless it is compiled out (scene.glsl has the measurements).

use std::cell::OnceCell;

use crate::gpu::{Context, GpuResult, Kernel};
use crate::scene::gpu::SceneFeatures;

pub struct SceneKernel {
    ctx: Context,
    name: &'static str,
    /// By SceneFeatures::index, plus 8 when the kernel's own constant is given false and 16
    /// when true (so a kernel's own default never shares a slot with an explicit value).
    variants: [OnceCell<Kernel>; 24],
    /// With two constants of the kernel's own: by SceneFeatures::index, plus 8 for constant
    /// 3 and 16 for constant 4 when true.
    pairs: [OnceCell<Kernel>; 32],
}

impl SceneKernel {
    /// Builds nothing yet, but checks that the kernel is embedded and its layout reflects.
    pub fn new(ctx: &Context, name: &'static str) -> GpuResult<Self> {
        Kernel::check_embedded(name)?;
        Ok(SceneKernel {
            ctx: ctx.clone(),
            name,
            variants: Default::default(),
            pairs: Default::default(),
        })
    }

    /// The kernel for a scene with `features` (a constant 3 of the kernel's own keeps the
    /// module's default).
    pub fn get(&self, features: SceneFeatures) -> GpuResult<&Kernel> {
        self.build(features, None)
    }

    /// The kernel for a scene with `features`, its constant 3 set to `flag`.
    pub fn get_with(&self, features: SceneFeatures, flag: bool) -> GpuResult<&Kernel> {
        self.build(features, Some(flag))
    }

    /// The kernel for a scene with `features`, its constants 3 and 4 set to `flags`.
    pub fn get_with_pair(&self, features: SceneFeatures, flags: [bool; 2]) -> GpuResult<&Kernel> {
        let cell =
            &self.pairs[features.index() + 8 * usize::from(flags[0]) + 16 * usize::from(flags[1])];
        if let Some(kernel) = cell.get() {
            return Ok(kernel);
        }
        let mut constants = features.constants().to_vec();
        constants.extend(flags.map(u32::from));
        let _ = cell.set(Kernel::specialized(&self.ctx, self.name, &constants)?);
        Ok(cell.get().expect("set above"))
    }

    fn build(&self, features: SceneFeatures, flag: Option<bool>) -> GpuResult<&Kernel> {
        let own = match flag {
            None => 0,
            Some(false) => 1,
            Some(true) => 2,
        };
        let cell = &self.variants[features.index() + 8 * own];
        if let Some(kernel) = cell.get() {
            return Ok(kernel);
        }
        let mut constants = features.constants().to_vec();
        constants.extend(flag.map(u32::from));
        let _ = cell.set(Kernel::specialized(&self.ctx, self.name, &constants)?);
        Ok(cell.get().expect("set above"))
    }
}
