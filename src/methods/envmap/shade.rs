//! glsl/shade_env.comp: the environment map's direct light at every G-buffer point, with a
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
}

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
        let params = ShadeParams {
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
        };
        self.0
            .dispatch(cmd, &bindings, &params, scene.image_workgroups())
    }
}
