//! glsl/bundles/shade_bundle_paths.comp: the environment's direct light through each G-buffer point's
//! bundle rays, and its one- and two-bounce paths through the chunk's VPLs and bundle hits,
//! MIS-combined (Tokuyoshi 12 Eq. 3-8), added into the accumulation.

use bytemuck::{Pod, Zeroable};

use crate::gpu::{bind, Buffer, Commands, Context, GpuResult};
use crate::methods::accumulation::Accumulation;
use crate::methods::gbuffer::GBuffer;
use crate::methods::scene_kernel::SceneKernel;
use crate::scene::gpu::GpuScene;

use super::directions::BundleDirections;
use super::light_vertices::FrameLightVertices;
use super::ray_bundles::BundleHit;
use super::{Strategy, Suppression};

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct ShadeParams {
    first_index: u32,
    count: u32,
    per_frame: u32,
    strategy: u32,
    beta: f32,
    two_bounce: f32,
    samples: u32,
    suppression: u32,
    suppression_parameter: f32,
    slots: u32,
    directions: u32,
    environment: u32,
    trace_bundles: u32,
    frame_first: u32,
    seed: u32,
    compensate: u32,
    hit_first: u32,
}

/// The GLSL layouts the structs above mirror (src/gpu/contracts.rs checks them).
#[cfg(test)]
pub(crate) const GPU_LAYOUTS: &[crate::gpu::contracts::GpuLayout] = {
    use crate::gpu::contracts::gpu_layout;
    &[gpu_layout!(ShadeParams in ["shade_bundle_paths"] {
        first_index,
        count,
        per_frame,
        strategy,
        beta,
        two_bounce,
        samples,
        suppression,
        suppression_parameter,
        slots,
        directions,
        environment,
        trace_bundles,
        frame_first,
        seed,
        compensate,
        hit_first,
    })]
};

/// Shadow rays per invocation in one dispatch: lavapipe stops an invocation's loops silently
/// after 65535 iterations in all (docs/DESIGN.md "The loop budget"), and a ray's traversal loop
/// runs tens of iterations in the shipped scenes (as ir's gather, 512 VPL slots per dispatch).
/// An iteration casts up to 4 rays per light vertex (VPL path, bundle path, two-bounce path,
/// compensation) and one more for the compensation's y.
const RAYS_PER_DISPATCH: u32 = 512;

/// What one chunk of iterations shades.
pub struct Chunk {
    /// The chunk's first iteration of the frame.
    pub first_index: u32,
    pub count: u32,
    /// Iterations per frame: each adds 1 / per_frame of its estimate.
    pub per_frame: u32,
    /// Iterations in the whole render: the N of the sample densities (Section 5.2).
    pub samples: u32,
    /// Whether the chunk's bundle hits were traced (not for the VPL paths alone).
    pub traced: bool,
    /// The frame's first iteration of the render (frame * per_frame): keys the chunk's
    /// random numbers.
    pub frame_first: u32,
}

/// Which paths the shading adds, besides the one-bounce paths of `strategy`.
pub struct Shading {
    pub strategy: Strategy,
    pub beta: f32,
    /// None leaves the two-bounce paths out; Some(0) shades them unclamped, Some(g) clamps
    /// their x1-x2 geometry term at g.
    pub two_bounce: Option<f32>,
    /// Add back what the two-bounce clamp removed (Kollig and Keller 2004), so the clamp
    /// leaves no bias.
    pub compensate: bool,
    /// Seed of the compensation's random numbers.
    pub seed: u32,
    /// Applies to the one-bounce paths and the environment's direct light.
    pub suppression: Suppression,
    /// The environment's direct light through the bundles.
    pub environment: bool,
}

pub struct ShadeBundlePaths(SceneKernel);

impl ShadeBundlePaths {
    pub fn new(ctx: &Context) -> GpuResult<Self> {
        Ok(ShadeBundlePaths(SceneKernel::new(
            ctx,
            "shade_bundle_paths",
        )?))
    }

    #[allow(clippy::too_many_arguments)]
    pub fn record<'a>(
        &'a self,
        cmd: &mut Commands<'a>,
        scene: &'a GpuScene,
        gbuffer: &'a GBuffer,
        vertices: &'a FrameLightVertices,
        directions: &'a BundleDirections,
        hits: &'a Buffer<BundleHit>,
        accumulation: &'a Accumulation,
        chunk: &Chunk,
        shading: &Shading,
    ) -> GpuResult<()> {
        let mut bindings = scene.bindings();
        bindings.push(bind("GBuffer", &gbuffer.texels));
        bindings.extend(accumulation.bindings());
        bindings.push(bind("LightVertices", &vertices.buffer));
        bindings.push(bind("BundleHits", hits));
        bindings.extend(directions.bindings());
        let suppression = shading.suppression;
        let mut params = ShadeParams {
            first_index: chunk.first_index,
            count: chunk.count,
            per_frame: chunk.per_frame,
            // Declared in the order of the GLSL's STRATEGY_* codes (a unit test checks them).
            strategy: shading.strategy as u32,
            beta: shading.beta,
            two_bounce: shading.two_bounce.map_or(-1.0, |g| g.max(0.0)),
            samples: chunk.samples,
            suppression: match suppression {
                Suppression::None => 0,
                Suppression::Roughness { .. } => 1,
                Suppression::Contribution { .. } => 2,
            },
            suppression_parameter: match suppression {
                Suppression::None => 0.0,
                Suppression::Roughness { m_prime } => m_prime,
                Suppression::Contribution { max } => max,
            },
            slots: vertices.slots,
            directions: directions.mode_code(),
            environment: shading.environment as u32,
            trace_bundles: chunk.traced as u32,
            frame_first: chunk.frame_first,
            seed: shading.seed,
            compensate: shading.compensate as u32,
            hit_first: 0,
        };
        let kernel = self.0.get(scene.features)?;
        let per_dispatch = (RAYS_PER_DISPATCH / (4 * vertices.slots + 1)).max(1);
        let mut begin = 0;
        while begin < chunk.count {
            let count = per_dispatch.min(chunk.count - begin);
            params.first_index = chunk.first_index + begin;
            params.count = count;
            params.hit_first = begin;
            kernel.dispatch(cmd, &bindings, &params, scene.image_workgroups())?;
            begin += count;
        }
        Ok(())
    }
}
