//! The render every method shares (docs/DESIGN.md "A render and a frame"): the G-buffer and the
//! accumulation, each frame's "gbuffer" and "direct light" passes, progressive submissions
//! with progress (progressive.rs), pass timings, the non-finite count and the `RenderOutput`.
//! A method brings what is its own: the buffers and tables it sets up once per render, the
//! passes it records each frame after the direct light (`MethodFrames::record`), and what it
//! adds to the output (`MethodFrames::finish`: stats, per-pixel maps).

use std::time::Instant;

use crate::gpu::{Commands, Context, GpuResult};
use crate::image::Image;
use crate::scene::gpu::GpuScene;

use super::accumulation::Accumulation;
use super::direct::{DirectLightOptions, FrameKeys, GBufferAndDirectLight};
use super::gbuffer::{GBuffer, PixelSampling};
use super::progressive;
use super::RenderOutput;

/// What every frame's own passes read besides the method's state.
pub struct Shared<'a> {
    /// The G-buffer and direct-light kernels (the reference runs their path tracer).
    pub passes: &'a GBufferAndDirectLight,
    pub scene: &'a GpuScene,
    pub gbuffer: &'a GBuffer,
    pub accumulation: &'a Accumulation,
}

/// A method's render once set up: its per-frame passes and its additions to the output.
pub trait MethodFrames {
    /// Records frame `frame`'s passes that go before its G-buffer (tables rebuilt each
    /// frame); none by default.
    fn record_first<'a>(&'a self, cmd: &mut Commands<'a>, frame: u32) -> GpuResult<()> {
        let _ = (cmd, frame);
        Ok(())
    }

    /// Records frame `frame`'s passes after the G-buffer and the direct light.
    fn record<'a>(
        &'a self,
        shared: &Shared<'a>,
        cmd: &mut Commands<'a>,
        frame: u32,
    ) -> GpuResult<()>;

    /// Stats and per-pixel maps, read once every frame has run.
    fn finish(&self, shared: &Shared<'_>) -> GpuResult<Extras> {
        let _ = shared;
        Ok(Extras::default())
    }
}

/// What a method adds to its `RenderOutput`.
#[derive(Default)]
pub struct Extras {
    pub stats: Vec<(String, f64)>,
    pub maps: Vec<(String, Image)>,
}

/// How the shared part of a render runs.
pub struct Plan {
    /// Frames to accumulate (at least 1).
    pub frames: u32,
    pub seed: u32,
    pub pixels: PixelSampling,
    /// The direct-light pass each frame records after the G-buffer, or none.
    pub direct: Option<DirectLightOptions>,
    /// When the render began (before the method's setup), for `RenderOutput::wall_ms`.
    pub start: Instant,
}

/// Renders `plan.frames` frames: per frame the G-buffer, the direct light and `method`'s own
/// passes, in progressive submissions; then the mean image, the timings and `method`'s extras.
pub fn render<'m>(
    ctx: &Context,
    passes: &GBufferAndDirectLight,
    scene: &GpuScene,
    plan: Plan,
    setup: impl FnOnce() -> GpuResult<Box<dyn MethodFrames + 'm>>,
    progress: impl FnMut(u32, u32),
) -> GpuResult<RenderOutput> {
    let gbuffer = GBuffer::new(ctx, scene)?;
    let accumulation = Accumulation::new(ctx, scene.width, scene.height)?;
    let method = setup()?;
    let shared = Shared {
        passes,
        scene,
        gbuffer: &gbuffer,
        accumulation: &accumulation,
    };
    let frames = plan.frames.max(1);
    let timings = progressive::run(
        ctx,
        scene,
        frames,
        &accumulation,
        |cmd, frame| {
            method.record_first(cmd, frame)?;
            let keys = FrameKeys {
                frame,
                seed: plan.seed,
                pixels: plan.pixels,
            };
            passes.record(cmd, scene, &gbuffer, &accumulation, keys, plan.direct)?;
            method.record(&shared, cmd, frame)
        },
        progress,
    )?;
    let extras = method.finish(&shared)?;
    Ok(RenderOutput {
        image: accumulation.resolve(frames),
        passes: timings,
        wall_ms: plan.start.elapsed().as_secs_f64() * 1e3,
        nonfinite_estimates: accumulation.nonfinite_estimates()?,
        stats: extras.stats,
        maps: extras.maps,
    })
}
