//! glsl/bundles/trace_ray_bundles.comp: global ray bundles (Tokuyoshi 12 Section 3.2) traced through
//! the BVH: for each iteration of a chunk, every G-buffer point's first hit along the shared
//! direction.

use bytemuck::{Pod, Zeroable};
use glam::Vec4;

use crate::gpu::{bind, Buffer, Commands, Context, GpuResult, Kernel};
use crate::methods::gbuffer::GBuffer;
use crate::scene::gpu::GpuScene;

use super::light_vertices::FrameLightVertices;

/// One bundle ray's first hit as glsl/include/bundles.glsl lays it out.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct BundleHit {
    /// x2; w: distance from x3, negative for none.
    pub position: Vec4,
    /// x: GPU triangle; y, z: barycentrics (f32 bits).
    pub triangle: [u32; 4],
}

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct BundleParams {
    first_index: u32,
    slots: u32,
}

/// The GLSL layouts the structs above mirror (src/gpu/contracts.rs checks them).
#[cfg(test)]
pub(crate) const GPU_LAYOUTS: &[crate::gpu::contracts::GpuLayout] = {
    use crate::gpu::contracts::gpu_layout;
    &[
        gpu_layout!(BundleHit as "BundleHit" { position, triangle }),
        gpu_layout!(BundleParams in ["trace_ray_bundles"] { first_index, slots }),
    ]
};

pub struct TraceRayBundles(Kernel);

impl TraceRayBundles {
    pub fn new(ctx: &Context) -> GpuResult<Self> {
        Ok(TraceRayBundles(Kernel::new(ctx, "trace_ray_bundles")?))
    }

    /// Traces the bundles of the frame's iterations `first_index..first_index + count` into
    /// `hits` (count times the pixel count entries, iteration-major).
    #[allow(clippy::too_many_arguments)]
    pub fn record<'a>(
        &'a self,
        cmd: &mut Commands<'a>,
        scene: &'a GpuScene,
        gbuffer: &'a GBuffer,
        vertices: &'a FrameLightVertices,
        hits: &'a Buffer<BundleHit>,
        first_index: u32,
        count: u32,
    ) -> GpuResult<()> {
        let mut bindings = scene.bindings();
        bindings.push(bind("GBuffer", &gbuffer.texels));
        bindings.push(bind("LightVertices", &vertices.buffer));
        bindings.push(bind("BundleHits", hits));
        let [x, y, _] = scene.image_workgroups();
        let params = BundleParams {
            first_index,
            slots: vertices.slots,
        };
        self.0.dispatch(cmd, &bindings, &params, [x, y, count])
    }
}
