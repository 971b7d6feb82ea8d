//! The start of every many-light method's frame: the G-buffer pass, then the paths kernel at
//! `max_depth` 1 (emission seen plus next-event estimation and BSDF sampling, MIS-combined:
//! the same direct light as the reference) or 0 (emission only, when the VPLs carry direct
//! light too), so methods differ only in how they estimate indirect light.

use crate::gpu::{Commands, Context, GpuResult};
use crate::scene::gpu::GpuScene;

use super::accumulation::Accumulation;
use super::gbuffer::{GBuffer, PixelSampling, WriteGBuffer};
use super::paths::{PathStarts, TracePaths};

/// The most `--direct-spp` accepts: more direct samples than a frame's VPL gather costs
/// rays is never the budget's best split.
pub const MAX_DIRECT_SPP: u32 = 1024;

pub struct GBufferAndDirectLight {
    gbuffer: WriteGBuffer,
    paths: TracePaths,
}

impl GBufferAndDirectLight {
    pub fn new(ctx: &Context) -> GpuResult<Self> {
        Ok(GBufferAndDirectLight {
            gbuffer: WriteGBuffer::new(ctx)?,
            paths: TracePaths::new(ctx)?,
        })
    }

    /// Records the passes "gbuffer" and "direct light" of `frame`; `reflected_environment`
    /// false leaves the environment's direct light out (bundles estimates it). `direct_spp` 0 or 1
    /// starts the direct-light paths at the G-buffer's hits; K > 1 gives them K camera rays of
    /// their own per pixel and frame (`--direct-spp`), so direct light and the pixel footprint
    /// get K samples while the frame's expensive indirect estimate gets one position.
    #[allow(clippy::too_many_arguments)]
    pub fn record<'a>(
        &'a self,
        cmd: &mut Commands<'a>,
        scene: &'a GpuScene,
        gbuffer: &'a GBuffer,
        accumulation: &'a Accumulation,
        frame: u32,
        seed: u32,
        pixels: PixelSampling,
        max_depth: u32,
        reflected_environment: bool,
        direct_spp: u32,
    ) -> GpuResult<()> {
        // One sample from its own camera ray would be the G-buffer's (sample index and
        // subpixel position `frame`): the G-buffer's hit saves the ray.
        let starts = match direct_spp {
            0 | 1 => PathStarts::GBuffer,
            samples => PathStarts::Camera { samples, pixels },
        };
        cmd.pass("gbuffer", |cmd| {
            self.gbuffer
                .record(cmd, scene, gbuffer, frame, seed, pixels)
        })?;
        cmd.pass("direct light", |cmd| {
            self.paths.record(
                cmd,
                scene,
                gbuffer,
                accumulation,
                frame,
                seed,
                max_depth,
                u32::MAX,
                reflected_environment,
                starts,
            )
        })
    }
}
