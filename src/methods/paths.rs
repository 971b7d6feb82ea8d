//! glsl/shared/trace_reference_paths.comp: one path per pixel from the G-buffer's first hit, adding
//! its estimate into the accumulation. The reference runs it with a deep `max_depth`; the
//! many-light methods run it with `max_depth` 1 for direct light (emission plus next-event
//! estimation and BSDF sampling, MIS-combined), so they differ only in indirect light, or 0
//! for the emission the camera sees. `reflected_environment` false leaves the environment's
//! light on surfaces out (the camera still sees the map) for a method that estimates it itself.

use bytemuck::{Pod, Zeroable};

use crate::gpu::{bind, Commands, Context, GpuResult};
use crate::scene::gpu::GpuScene;

use super::accumulation::Accumulation;
use super::gbuffer::{GBuffer, PixelSampling};
use super::scene_kernel::SceneKernel;

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct PathParams {
    frame: u32,
    seed: u32,
    max_depth: u32,
    roulette_depth: u32,
    environment: u32,
    camera_samples: u32,
    first_sample: u32,
    sample_count: u32,
    centred: u32,
}

/// The GLSL layouts the structs above mirror (src/gpu/contracts.rs checks them).
#[cfg(test)]
pub(crate) const GPU_LAYOUTS: &[crate::gpu::contracts::GpuLayout] = {
    use crate::gpu::contracts::gpu_layout;
    &[gpu_layout!(PathParams in ["trace_reference_paths"] {
        frame,
        seed,
        max_depth,
        roulette_depth,
        environment,
        camera_samples,
        first_sample,
        sample_count,
        centred,
    })]
};

/// Where a frame's paths start.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PathStarts {
    /// One path per pixel from the G-buffer's hit (the reference's frame).
    GBuffer,
    /// `samples` paths per pixel, each from its own camera ray (new subpixel positions,
    /// sample indices frame * samples + k), averaged: a many-light method's `--direct-spp`.
    Camera { samples: u32, pixels: PixelSampling },
}

/// How next-event estimation chooses its light (the kernel's constant LIGHT_BVH).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum LightSampler {
    /// In proportion to power, from the light table (src/scene/gpu.rs).
    #[default]
    Power,
    /// Through the light BVH (glsl/include/light_bvh.glsl, src/sampling/light_bvh.rs).
    Bvh,
}

crate::methods::settings::named_choices!(LightSampler {
    Power => "power",
    Bvh => "bvh",
});

/// Camera samples per pixel in one dispatch: lavapipe stops an invocation's loops silently
/// after 65535 iterations in all (docs/DESIGN.md "The loop budget"); a depth-1 sample traces
/// three rays, each a traversal loop of up to a few hundred iterations in the largest scenes,
/// so 16 samples stay well inside the budget and more are split across dispatches.
const CAMERA_SAMPLES_PER_DISPATCH: u32 = 16;

/// The kernel, specialized to each scene's features, to where paths start (its constant
/// CAMERA_STARTS) and to how lights are chosen (LIGHT_BVH).
pub struct TracePaths(SceneKernel);

impl TracePaths {
    pub fn new(ctx: &Context) -> GpuResult<Self> {
        Ok(TracePaths(SceneKernel::new(ctx, "trace_reference_paths")?))
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
        starts: PathStarts,
        sampler: LightSampler,
    ) -> GpuResult<()> {
        let kernel = self.0.get_with_pair(
            scene.features,
            [starts != PathStarts::GBuffer, sampler == LightSampler::Bvh],
        )?;
        let mut bindings = scene.bindings();
        bindings.extend(scene.light_bvh_bindings());
        bindings.push(bind("GBuffer", &gbuffer.texels));
        bindings.extend(accumulation.bindings());
        let mut params = PathParams {
            frame,
            seed,
            max_depth,
            roulette_depth,
            environment: reflected_environment as u32,
            camera_samples: 0,
            first_sample: 0,
            sample_count: 0,
            centred: 0,
        };
        match starts {
            PathStarts::GBuffer => {
                kernel.dispatch(cmd, &bindings, &params, scene.image_workgroups())
            }
            PathStarts::Camera { samples, pixels } => {
                let samples = samples.max(1);
                params.camera_samples = samples;
                params.centred = u32::from(pixels == PixelSampling::Centres);
                let mut first = 0;
                while first < samples {
                    params.first_sample = first;
                    params.sample_count = CAMERA_SAMPLES_PER_DISPATCH.min(samples - first);
                    // (Each dispatch adds into the same pixels; dispatches are ordered by
                    // the barrier Commands records after each.)
                    kernel.dispatch(cmd, &bindings, &params, scene.image_workgroups())?;
                    first += params.sample_count;
                }
                Ok(())
            }
        }
    }
}
