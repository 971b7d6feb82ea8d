//! The reference path tracer, ground truth for every accuracy figure: per frame, the G-buffer
//! pass then glsl/trace_reference_paths.comp (one path per pixel: next-event estimation plus
//! BSDF sampling combined by the power heuristic, Russian roulette), accumulated over `spp`
//! frames. Unbiased up to `max_depth` scattering events (a safety cap; Russian roulette ends
//! paths long before it unless the scene reflects almost everything).

use std::time::Instant;

use bytemuck::{Pod, Zeroable};

use crate::gpu::{Commands, Context, GpuResult, Kernel, PassTotals};
use crate::image::Image;
use crate::scene::gpu::GpuScene;

use super::accumulation::Accumulation;
use super::gbuffer::{GBuffer, WriteGBuffer};

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ReferenceSettings {
    /// Samples (paths) per pixel, one per frame.
    pub spp: u32,
    pub seed: u32,
    /// Most scattering events per path.
    pub max_depth: u32,
    /// First bounce at which Russian roulette may end a path.
    pub roulette_depth: u32,
}

impl Default for ReferenceSettings {
    fn default() -> Self {
        ReferenceSettings {
            spp: 64,
            seed: 0,
            max_depth: 1024,
            roulette_depth: 3,
        }
    }
}

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct PathParams {
    frame: u32,
    seed: u32,
    max_depth: u32,
    roulette_depth: u32,
}

pub struct RenderOutput {
    pub image: Image,
    pub passes: PassTotals,
    /// Wall clock of the whole render on the host, submissions and waits included.
    pub wall_ms: f64,
    /// Per-pixel estimates that were NaN or Inf and were dropped (0 in a correct run).
    pub nonfinite_estimates: u32,
}

pub struct Reference {
    gbuffer: WriteGBuffer,
    paths: Kernel,
}

impl Reference {
    pub fn new(ctx: &Context) -> GpuResult<Reference> {
        Ok(Reference {
            gbuffer: WriteGBuffer::new(ctx)?,
            paths: Kernel::new(ctx, "trace_reference_paths")?,
        })
    }

    /// Renders `settings.spp` frames, calling `progress(frames_done, spp)` after each
    /// submission. Submissions grow to about a quarter second each so progress stays live.
    pub fn render(
        &self,
        ctx: &Context,
        scene: &GpuScene,
        settings: &ReferenceSettings,
        mut progress: impl FnMut(u32, u32),
    ) -> GpuResult<RenderOutput> {
        let start = Instant::now();
        let gbuffer = GBuffer::new(ctx, scene)?;
        let mut accumulation = Accumulation::new(ctx, scene.width, scene.height)?;
        let mut passes = PassTotals::default();
        let spp = settings.spp.max(1);
        let mut done = 0u32;
        let mut batch = 1u32;
        while done < spp {
            let frames = batch.min(spp - done).min(200);
            let mut cmd = Commands::new(ctx)?;
            accumulation.begin_submission(&mut cmd);
            for frame in done..done + frames {
                self.record_frame(&mut cmd, scene, &gbuffer, &accumulation, frame, settings)?;
            }
            let timings = cmd.submit_and_wait()?;
            accumulation.collect()?;
            passes.add(&timings);
            done += frames;
            progress(done, spp);
            let per_frame_ms = timings.wall_ms / frames as f64;
            batch = ((250.0 / per_frame_ms.max(1e-3)) as u32).clamp(1, 200);
        }
        Ok(RenderOutput {
            image: accumulation.resolve(spp),
            passes,
            wall_ms: start.elapsed().as_secs_f64() * 1e3,
            nonfinite_estimates: accumulation.nonfinite_estimates()?,
        })
    }

    fn record_frame<'a>(
        &'a self,
        cmd: &mut Commands<'a>,
        scene: &'a GpuScene,
        gbuffer: &'a GBuffer,
        accumulation: &'a Accumulation,
        frame: u32,
        settings: &ReferenceSettings,
    ) -> GpuResult<()> {
        cmd.pass("gbuffer", |cmd| {
            self.gbuffer
                .record(cmd, scene, gbuffer, frame, settings.seed)
        })?;
        cmd.pass("reference paths", |cmd| {
            let mut bindings = scene.bindings();
            bindings.push(crate::gpu::bind("GBuffer", &gbuffer.texels));
            bindings.extend(accumulation.bindings());
            let params = PathParams {
                frame,
                seed: settings.seed,
                max_depth: settings.max_depth,
                roulette_depth: settings.roulette_depth,
            };
            self.paths.dispatch(
                cmd,
                &bindings,
                &params,
                [scene.width.div_ceil(8), scene.height.div_ceil(8), 1],
            )
        })?;
        Ok(())
    }
}
