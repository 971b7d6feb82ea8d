//! Bidirectional instant radiosity (Segovia 06), method `bir`: VPLs from the lights (standard,
//! Keller's walk as in `ir`) and from the camera (reverse: the ends of length-2 camera paths,
//! Section 3.1), per frame. Direct light is the reference's next-event estimation; the VPLs
//! carry indirect light. `--strategy standard` shades standard VPLs only (ir's estimator),
//! `reverse` reverse VPLs only (standard VPLs then only light the reverse ones), `both` each
//! side at weight 1/2: two unbiased estimators of the same indirect light, averaged.
//!
//! Budget: `vpls` VPLs per frame. The standard side gets the light paths whose fractional
//! absorption schedule yields about its share of surface VPLs (Keller: N rho / (1 - rho)); the
//! reverse side its share of reverse VPLs. `standard` gives its whole budget to the standard
//! side; `reverse` to the reverse side, plus half a budget of light paths that light them;
//! `both` half to each.

pub mod reverse;

use std::time::Instant;

use thiserror::Error;

use crate::gpu::{Buffer, Context, GpuError};
use crate::methods::accumulation::Accumulation;
use crate::methods::gbuffer::{GBuffer, PixelSampling, WriteGBuffer};
use crate::methods::ir::gather::AccumulateVpls;
use crate::methods::ir::schedule::{mean_albedo, Absorption, Schedule};
use crate::methods::ir::walk::{TraceVpls, Vpl, VplBuffers};
use crate::methods::paths::TracePaths;
use crate::methods::progressive;
use crate::methods::RenderOutput;
use crate::sampling::pcg;
use crate::scene::gpu::GpuScene;
use crate::scene::Scene;

use reverse::{ShadeReverseVpls, TraceReverseVpls};

/// Which VPLs a frame shades.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Strategy {
    Standard,
    Reverse,
    Both,
}

impl Strategy {
    pub fn name(self) -> &'static str {
        match self {
            Strategy::Standard => "standard",
            Strategy::Reverse => "reverse",
            Strategy::Both => "both",
        }
    }
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BirSettings {
    /// VPLs per frame (standard and reverse together).
    pub vpls: u32,
    pub frames: u32,
    pub seed: u32,
    pub strategy: Strategy,
    /// Camera points per frame the reverse VPLs start from (Eq. 7's M).
    pub pool: u32,
    /// Next-event samples per reverse VPL for its radiance.
    pub light_samples: u32,
    pub pixels: PixelSampling,
}

impl Default for BirSettings {
    fn default() -> Self {
        BirSettings {
            vpls: 256,
            frames: 16,
            seed: 0,
            strategy: Strategy::Both,
            pool: 50,
            light_samples: 4,
            pixels: PixelSampling::Jittered,
        }
    }
}

#[derive(Debug, Error)]
pub enum BirError {
    #[error("bir does not support environment lights: standard VPLs start on emissive triangles, point and spot lights (use --method reference)")]
    Environment,
    #[error(transparent)]
    Gpu(#[from] GpuError),
}

/// How a frame's budget splits.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Split {
    /// Light paths of the standard walk.
    pub light_paths: u32,
    pub reverse: u32,
    /// Weights of the standard and reverse sides in the image.
    pub standard_weight: f32,
    pub reverse_weight: f32,
}

impl Split {
    pub fn new(settings: &BirSettings, mean_albedo: f64) -> Split {
        let n = settings.vpls.max(2);
        // Light paths that give about `vpls` surface VPLs: N rho / (1 - rho) of them.
        let paths_for = |vpls: u32| -> u32 {
            let rho = mean_albedo.clamp(0.05, 0.95);
            ((vpls as f64 * (1.0 - rho) / rho).ceil() as u32).max(1)
        };
        match settings.strategy {
            Strategy::Standard => Split {
                light_paths: paths_for(n),
                reverse: 0,
                standard_weight: 1.0,
                reverse_weight: 0.0,
            },
            Strategy::Reverse => Split {
                light_paths: paths_for(n / 2),
                reverse: n,
                standard_weight: 0.0,
                reverse_weight: 1.0,
            },
            Strategy::Both => Split {
                light_paths: paths_for(n / 2),
                reverse: n - n / 2,
                standard_weight: 0.5,
                reverse_weight: 0.5,
            },
        }
    }
}

pub struct Bir {
    gbuffer: WriteGBuffer,
    paths: TracePaths,
    walk: TraceVpls,
    trace_reverse: TraceReverseVpls,
    shade_reverse: ShadeReverseVpls,
    gather: AccumulateVpls,
}

impl Bir {
    pub fn new(ctx: &Context) -> Result<Self, GpuError> {
        Ok(Bir {
            gbuffer: WriteGBuffer::new(ctx)?,
            paths: TracePaths::new(ctx)?,
            walk: TraceVpls::new(ctx)?,
            trace_reverse: TraceReverseVpls::new(ctx)?,
            shade_reverse: ShadeReverseVpls::new(ctx)?,
            gather: AccumulateVpls::new(ctx)?,
        })
    }

    pub fn render(
        &self,
        ctx: &Context,
        scene: &Scene,
        gpu_scene: &GpuScene,
        settings: &BirSettings,
        progress: impl FnMut(u32, u32),
    ) -> Result<RenderOutput, BirError> {
        if scene.environment.is_some() {
            return Err(BirError::Environment);
        }
        let start = Instant::now();
        let rho = mean_albedo(scene);
        let split = Split::new(settings, rho);
        let gbuffer = GBuffer::new(ctx, gpu_scene)?;
        let accumulation = Accumulation::new(ctx, gpu_scene.width, gpu_scene.height)?;
        let vpls = VplBuffers::new(
            ctx,
            Schedule::new(split.light_paths, rho, Absorption::Fractional),
        )?;
        let reverse: Buffer<Vpl> =
            Buffer::zeroed(ctx, "ReverseVpls", split.reverse.max(1) as usize)?;
        let unused = Buffer::zeroed(ctx, "VplRadiance", 1)?;
        let slots = vpls.layout.surface_slots();
        let frames = settings.frames.max(1);
        let passes = progressive::run(
            ctx,
            frames,
            &accumulation,
            |cmd, frame| {
                cmd.pass("gbuffer", |cmd| {
                    self.gbuffer.record(
                        cmd,
                        gpu_scene,
                        &gbuffer,
                        frame,
                        settings.seed,
                        settings.pixels,
                    )
                })?;
                cmd.pass("direct light", |cmd| {
                    self.paths.record(
                        cmd,
                        gpu_scene,
                        &gbuffer,
                        &accumulation,
                        frame,
                        settings.seed,
                        1,
                        u32::MAX,
                    )
                })?;
                let walk_seed = pcg::hash(&[settings.seed, frame, 0x76706c73]);
                cmd.pass("vpl walk", |cmd| {
                    self.walk.record(cmd, gpu_scene, &vpls, walk_seed)
                })?;
                if split.reverse > 0 {
                    let reverse_seed = pcg::hash(&[settings.seed, frame, 0x72657672]);
                    cmd.pass("reverse vpls", |cmd| {
                        self.trace_reverse.record(
                            cmd,
                            gpu_scene,
                            &gbuffer,
                            &reverse,
                            settings.pool,
                            reverse_seed,
                        )
                    })?;
                    cmd.pass("reverse radiance", |cmd| {
                        self.shade_reverse.record(
                            cmd,
                            gpu_scene,
                            &reverse,
                            &vpls.vpls,
                            slots.clone(),
                            settings.light_samples,
                            reverse_seed,
                            split.reverse_weight,
                        )
                    })?;
                }
                cmd.pass("vpl accumulation", |cmd| {
                    if split.standard_weight > 0.0 {
                        self.gather.record(
                            cmd,
                            gpu_scene,
                            &gbuffer,
                            &vpls.vpls,
                            &accumulation,
                            &unused,
                            slots.clone(),
                            0.0,
                            1,
                            split.standard_weight,
                        )?;
                    }
                    if split.reverse > 0 {
                        // The reverse side's weight is in its VPLs' power.
                        self.gather.record(
                            cmd,
                            gpu_scene,
                            &gbuffer,
                            &reverse,
                            &accumulation,
                            &unused,
                            0..split.reverse,
                            0.0,
                            1,
                            1.0,
                        )?;
                    }
                    Ok(())
                })
            },
            progress,
        )?;
        Ok(RenderOutput {
            image: accumulation.resolve(frames),
            passes,
            wall_ms: start.elapsed().as_secs_f64() * 1e3,
            nonfinite_estimates: accumulation.nonfinite_estimates()?,
        })
    }
}
