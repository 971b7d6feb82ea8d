//! The start of every many-light method's frame: the G-buffer pass, then the paths kernel at
//! `max_depth` 1 (emission seen plus next-event estimation and BSDF sampling, MIS-combined:
//! the same direct light as the reference) or 0 (emission only, when the VPLs carry direct
//! light too), so methods differ only in how they estimate indirect light.

use crate::gpu::{Commands, Context, GpuResult};
use crate::scene::gpu::GpuScene;

use super::accumulation::Accumulation;
use super::gbuffer::{GBuffer, PixelSampling, WriteGBuffer};
use super::paths::{LightSampler, PathStarts, TracePaths};

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

    /// The path tracer the direct light runs (the reference runs it to full depth).
    pub fn paths(&self) -> &TracePaths {
        &self.paths
    }

    /// Records the passes "gbuffer" and "direct light" of `frame`, the direct light as
    /// `options` says (none: the G-buffer alone).
    pub fn record<'a>(
        &'a self,
        cmd: &mut Commands<'a>,
        scene: &'a GpuScene,
        gbuffer: &'a GBuffer,
        accumulation: &'a Accumulation,
        frame: FrameKeys,
        options: Option<DirectLightOptions>,
    ) -> GpuResult<()> {
        let FrameKeys {
            frame,
            seed,
            pixels,
        } = frame;
        cmd.pass("gbuffer", |cmd| {
            self.gbuffer
                .record(cmd, scene, gbuffer, frame, seed, pixels)
        })?;
        let Some(options) = options else {
            return Ok(());
        };
        // One sample from its own camera ray would be the G-buffer's (sample index and
        // subpixel position `frame`): the G-buffer's hit saves the ray.
        let starts = match options.spp {
            0 | 1 => PathStarts::GBuffer,
            samples => PathStarts::Camera { samples, pixels },
        };
        cmd.pass("direct light", |cmd| {
            self.paths.record(
                cmd,
                scene,
                gbuffer,
                accumulation,
                frame,
                seed,
                options.light.max_depth(),
                u32::MAX,
                options.reflected_environment,
                starts,
                LightSampler::Power,
            )
        })
    }
}

/// Which frame a pass records: its index, the render's seed and how pixels are sampled.
#[derive(Clone, Copy, Debug)]
pub struct FrameKeys {
    pub frame: u32,
    pub seed: u32,
    pub pixels: PixelSampling,
}

/// What the direct-light pass estimates.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DirectLightPaths {
    /// Emission seen from the camera, next-event estimation and BSDF sampling, MIS-combined
    /// (the paths kernel at `max_depth` 1).
    NextEvent,
    /// Emission seen from the camera only (`max_depth` 0): the method's VPLs carry direct
    /// light too.
    EmissionOnly,
}

impl DirectLightPaths {
    fn max_depth(self) -> u32 {
        match self {
            DirectLightPaths::NextEvent => 1,
            DirectLightPaths::EmissionOnly => 0,
        }
    }
}

/// The direct-light pass's options.
#[derive(Clone, Copy, Debug)]
pub struct DirectLightOptions {
    pub light: DirectLightPaths,
    /// false leaves the environment's direct light out (bundles estimates it).
    pub reflected_environment: bool,
    /// 0 or 1 starts the paths at the G-buffer's hits; K > 1 gives them K camera rays of
    /// their own per pixel and frame (`--direct-spp`), so direct light and the pixel footprint
    /// get K samples while the frame's expensive indirect estimate gets one position.
    pub spp: u32,
}
