//! glsl/trace_reference_paths.comp: one path per pixel from the G-buffer's first hit, adding
//! its estimate into the accumulation. The reference runs it with a deep `max_depth`; the
//! many-light methods run it with `max_depth` 1 for direct light (emission plus next-event
//! estimation and BSDF sampling, MIS-combined), so they differ only in indirect light, or 0
//! for the emission the camera sees. `reflected_environment` false leaves the environment's
//! light on surfaces out (the camera still sees the map) for a method that estimates it itself.

use bytemuck::{Pod, Zeroable};

use crate::gpu::{bind, Commands, Context, GpuResult, Kernel};
use crate::scene::gpu::GpuScene;

use super::accumulation::Accumulation;
use super::gbuffer::GBuffer;

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct PathParams {
    frame: u32,
    seed: u32,
    max_depth: u32,
    roulette_depth: u32,
    environment: u32,
}

pub struct TracePaths(Kernel);

impl TracePaths {
    pub fn new(ctx: &Context) -> GpuResult<Self> {
        Ok(TracePaths(Kernel::new(ctx, "trace_reference_paths")?))
    }

    #[allow(clippy::too_many_arguments)]
    pub fn record<'a>(
        &'a self,
        cmd: &mut Commands<'a>,
        scene: &'a GpuScene,
        gbuffer: &'a GBuffer,
        accumulation: &'a Accumulation,
        frame: u32,
        seed: u32,
        max_depth: u32,
        roulette_depth: u32,
        reflected_environment: bool,
    ) -> GpuResult<()> {
        let mut bindings = scene.bindings();
        bindings.push(bind("GBuffer", &gbuffer.texels));
        bindings.extend(accumulation.bindings());
        let params = PathParams {
            frame,
            seed,
            max_depth,
            roulette_depth,
            environment: reflected_environment as u32,
        };
        self.0
            .dispatch(cmd, &bindings, &params, scene.image_workgroups())
    }
}
