//! A kernel specialized to each scene it runs on: scene.glsl's SCENE_HAS_* specialization
//! constants (0-3) set from the scene's features, and optionally one more boolean of the
//! kernel's own (constant 4), or two (constants 4 and 5), built the first time a combination is
//! recorded. gallivm
//! (lavapipe) runs the code of every branch, taken or not, so code for what a scene lacks costs
//! its full time unless it is compiled out (scene.glsl has the measurements).

use std::cell::OnceCell;

use crate::gpu::{Context, GpuResult, Kernel};
use crate::scene::gpu::SceneFeatures;

/// Variants per value of a kernel's own constants: one per combination of scene features.
const VARIANTS: usize = 1 << SceneFeatures::COUNT;

pub struct SceneKernel {
    ctx: Context,
    name: &'static str,
    /// By SceneFeatures::index, plus VARIANTS when the kernel's own constant is given false
    /// and 2 VARIANTS when true (so a kernel's own default never shares a slot with an
    /// explicit value).
    variants: [OnceCell<Kernel>; 3 * VARIANTS],
    /// With two constants of the kernel's own: by SceneFeatures::index, plus VARIANTS for
    /// constant 4 and 2 VARIANTS for constant 5 when true.
    pairs: [OnceCell<Kernel>; 4 * VARIANTS],
}

impl SceneKernel {
    /// Builds nothing yet, but checks that the kernel is embedded and its layout reflects.
    pub fn new(ctx: &Context, name: &'static str) -> GpuResult<Self> {
        Kernel::check_embedded(name)?;
        Ok(SceneKernel {
            ctx: ctx.clone(),
            name,
            variants: std::array::from_fn(|_| OnceCell::new()),
            pairs: std::array::from_fn(|_| OnceCell::new()),
        })
    }

    /// The kernel for a scene with `features` (a constant 4 of the kernel's own keeps the
    /// module's default).
    pub fn get(&self, features: SceneFeatures) -> GpuResult<&Kernel> {
        self.build(features, None)
    }

    /// The kernel for a scene with `features`, its constant 4 set to `flag`.
    pub fn get_with(&self, features: SceneFeatures, flag: bool) -> GpuResult<&Kernel> {
        self.build(features, Some(flag))
    }

    /// The kernel for a scene with `features`, its constants 4 and 5 set to `flags`.
    pub fn get_with_pair(&self, features: SceneFeatures, flags: [bool; 2]) -> GpuResult<&Kernel> {
        let cell = &self.pairs[features.index()
            + VARIANTS * usize::from(flags[0])
            + 2 * VARIANTS * usize::from(flags[1])];
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
        let cell = &self.variants[features.index() + VARIANTS * own];
        if let Some(kernel) = cell.get() {
            return Ok(kernel);
        }
        let mut constants = features.constants().to_vec();
        constants.extend(flag.map(u32::from));
        let _ = cell.set(Kernel::specialized(&self.ctx, self.name, &constants)?);
        Ok(cell.get().expect("set above"))
    }
}
