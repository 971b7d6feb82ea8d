//! glsl/ir/filter_interleaved.comp: restores a full estimate per pixel from the k x k block of
//! interleaved VPL subsets (Keller and Heidrich 2001), across pixels that see the same surface.

use bytemuck::{Pod, Zeroable};
use glam::Vec4;

use crate::gpu::{bind, Buffer, Commands, Context, GpuResult, Kernel};
use crate::methods::accumulation::Accumulation;
use crate::methods::gbuffer::GBuffer;
use crate::scene::gpu::GpuScene;

/// Hit points within this fraction of the pixel's camera distance off its tangent plane...
pub const PLANE_TOLERANCE: f32 = 0.02;
/// ...and with normals at most ~25 degrees apart count as the same surface.
pub const NORMAL_TOLERANCE: f32 = 0.9;

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct FilterParams {
    interleave: u32,
    plane_tolerance: f32,
    normal_tolerance: f32,
    _pad: u32,
}

/// The GLSL layouts the structs above mirror (src/gpu/contracts.rs checks them).
#[cfg(test)]
pub(crate) const GPU_LAYOUTS: &[crate::gpu::contracts::GpuLayout] = {
    use crate::gpu::contracts::gpu_layout;
    &[gpu_layout!(FilterParams in ["filter_interleaved"] {
        interleave,
        plane_tolerance,
        normal_tolerance,
        _pad,
    })]
};

pub struct FilterInterleaved(Kernel);

impl FilterInterleaved {
    pub fn new(ctx: &Context) -> GpuResult<Self> {
        Ok(FilterInterleaved(Kernel::new(ctx, "filter_interleaved")?))
    }

    pub fn record<'a>(
        &'a self,
        cmd: &mut Commands<'a>,
        scene: &'a GpuScene,
        gbuffer: &'a GBuffer,
        vpl_radiance: &'a Buffer<Vec4>,
        accumulation: &'a Accumulation,
        interleave: u32,
    ) -> GpuResult<()> {
        let mut bindings = scene.scene_bindings();
        bindings.push(bind("GBuffer", &gbuffer.texels));
        bindings.extend(accumulation.bindings());
        bindings.push(bind("VplRadiance", vpl_radiance));
        let params = FilterParams {
            interleave,
            plane_tolerance: PLANE_TOLERANCE,
            normal_tolerance: NORMAL_TOLERANCE,
            _pad: 0,
        };
        self.0
            .dispatch(cmd, &bindings, &params, scene.image_workgroups())
    }
}
