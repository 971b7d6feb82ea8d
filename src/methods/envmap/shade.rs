//! glsl/envmap/shade_env.comp: the environment map's direct light at every G-buffer point, with a
//! shadow ray per sample, by the chosen strategy (Lu 14 Eq. 3.4-3.7, Alg. 2, and baselines).

use bytemuck::{Pod, Zeroable};

use crate::gpu::{bind, Buffer, Commands, Context, GpuResult, Kernel};
use crate::methods::accumulation::Accumulation;
use crate::methods::gbuffer::GBuffer;
use crate::scene::gpu::GpuScene;

use super::cube::CubeTable;
use super::pyramid::EnvPyramid;
use super::Strategy;
use crate::methods::equirect_table::EquirectTable;

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct ShadeParams {
    resolution: u32,
    per_face: u32,
    strategy: u32,
    spp: f32,
    frame: u32,
    seed: u32,
    light_share: f32,
    integer_counts: u32,
    alpha_samples: f32,
    shadows: u32,
    windows: u32,
    item_begin: u32,
    item_end: u32,
    alpha_step: u32,
}

/// The GLSL layouts the structs above mirror (src/gpu/contracts.rs checks them).
#[cfg(test)]
pub(crate) const GPU_LAYOUTS: &[crate::gpu::contracts::GpuLayout] = {
    use crate::gpu::contracts::gpu_layout;
    &[gpu_layout!(ShadeParams in ["shade_env"] {
        resolution,
        per_face,
        strategy,
        spp,
        frame,
        seed,
        light_share,
        integer_counts,
        alpha_samples,
        shadows,
        windows,
        item_begin,
        item_end,
        alpha_step,
    })]
};

/// Samples per pixel in one dispatch. lavapipe stops an invocation's loops silently after 65535
/// iterations in all (docs/DESIGN.md "The loop budget"); a sample costs one shadow ray (a
/// traversal loop: tens of iterations in the shipped scenes) and at most about 25 iterations of
/// table searches, so 128 samples stay inside the budget for traversals of up to ~400
/// iterations. Measured before the split (glossy-env 32x32, pixel centres, 1 frame): 16384
/// samples per pixel came out 10% dark, latlong's 8192 40%, 65536 36-80%.
pub const SAMPLES_PER_DISPATCH: u32 = 128;

/// What the shading does this frame.
pub struct ShadeSettings {
    pub strategy: Strategy,
    /// N_s.
    pub spp: u32,
    pub light_only: bool,
    pub integer_counts: bool,
    /// alpha: M.
    pub alpha_samples: u32,
    /// false: no shadow rays (the thesis's setting, for its timings; biased where occluded).
    pub shadows: bool,
    pub frame: u32,
    pub seed: u32,
}

impl ShadeSettings {
    /// The most samples a pixel numbers in one step (alpha: `step` 1 or 2; the others: 0):
    /// the fractional per-face counts of the cube strategies round up once per face and
    /// once for the BRDF share.
    fn items(&self, step: u32) -> u32 {
        let spp = self.spp.max(1);
        let rounding = 7;
        match (self.strategy, step) {
            (Strategy::Brdf | Strategy::Cosine, _) => spp,
            (Strategy::Latlong | Strategy::Hierarchical, _) => 2 * spp.div_ceil(2),
            (Strategy::Alpha, 1) => self.alpha_samples.min(spp) + rounding,
            (Strategy::Alpha, _) => spp - self.alpha_samples.min(spp) + rounding,
            _ => spp + rounding,
        }
    }
}

pub struct ShadeEnv(Kernel);

impl ShadeEnv {
    pub fn new(ctx: &Context) -> GpuResult<Self> {
        Ok(ShadeEnv(Kernel::new(ctx, "shade_env")?))
    }

    #[allow(clippy::too_many_arguments)]
    pub fn record<'a>(
        &'a self,
        cmd: &mut Commands<'a>,
        scene: &'a GpuScene,
        gbuffer: &'a GBuffer,
        cube: &'a CubeTable,
        latlong: &'a EquirectTable,
        pyramid: &'a EnvPyramid,
        accumulation: &'a Accumulation,
        counts: &'a Buffer<[f32; 2]>,
        alpha: &'a Buffer<[f32; 2]>,
        alpha_terms: &'a Buffer<[f32; 2]>,
        settings: &ShadeSettings,
    ) -> GpuResult<()> {
        let mut bindings = scene.bindings();
        bindings.push(bind("GBuffer", &gbuffer.texels));
        bindings.extend(accumulation.bindings());
        bindings.extend(cube.bindings());
        bindings.extend(latlong.bindings());
        bindings.push(bind("EnvSamples", &cube.samples));
        bindings.push(bind("EnvSampleCounts", counts));
        bindings.push(pyramid.binding());
        bindings.push(bind("EnvAlpha", alpha));
        bindings.push(bind("EnvAlphaTerms", alpha_terms));
        let mut params = ShadeParams {
            resolution: cube.resolution,
            per_face: cube.per_face,
            strategy: settings.strategy.code(),
            spp: settings.spp as f32,
            frame: settings.frame,
            seed: settings.seed,
            light_share: if settings.light_only { 1.0 } else { 0.5 },
            integer_counts: settings.integer_counts as u32,
            alpha_samples: settings.alpha_samples as f32,
            shadows: settings.shadows as u32,
            windows: cube.windows,
            item_begin: 0,
            item_end: 0,
            alpha_step: 0,
        };
        // Alpha's second step reads the alpha its first step's dispatches estimated.
        let steps: &[u32] = if settings.strategy == Strategy::Alpha {
            &[1, 2]
        } else {
            &[0]
        };
        for &step in steps {
            params.alpha_step = step;
            let items = settings.items(step);
            let mut begin = 0;
            // At least one dispatch per step (alpha's first writes its sums even when empty).
            loop {
                params.item_begin = begin;
                params.item_end = begin.saturating_add(SAMPLES_PER_DISPATCH);
                self.0
                    .dispatch(cmd, &bindings, &params, scene.image_workgroups())?;
                begin = params.item_end;
                if begin >= items {
                    break;
                }
            }
        }
        Ok(())
    }
}
