//! glsl/shared/write_gbuffer.comp: the first hit of one jittered camera ray per pixel (Keller 97
//! Section 4.1 low-discrepancy subpixel positions: per-pixel shifted Halton), shared by every method.

use bytemuck::{Pod, Zeroable};
use glam::Vec4;

use crate::gpu::{bind, Buffer, Commands, Context, GpuResult, Kernel};
use crate::scene::gpu::GpuScene;

#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct GBufferTexel {
    /// Hit point; w: hit distance, negative for a miss.
    pub position: Vec4,
    /// w: material index (u32 bits).
    pub shading_normal: Vec4,
    /// w: GPU triangle index (u32 bits).
    pub geometric_normal: Vec4,
    pub direction: Vec4,
}

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct FrameParams {
    frame: u32,
    seed: u32,
    centred: u32,
    _pad: u32,
}

/// The GLSL layouts the structs above mirror (src/gpu/contracts.rs checks them).
#[cfg(test)]
pub(crate) const GPU_LAYOUTS: &[crate::gpu::contracts::GpuLayout] = {
    use crate::gpu::contracts::gpu_layout;
    &[
        gpu_layout!(GBufferTexel as "GBufferTexel" {
            position,
            shading_normal,
            geometric_normal,
            direction,
        }),
        gpu_layout!(FrameParams in ["write_gbuffer"] { frame, seed, centred, _pad }),
    ]
};

/// Where in each pixel the camera rays go.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum PixelSampling {
    /// Low-discrepancy positions over the pixel, a new one each frame: the box-filtered
    /// pixel average (docs/DESIGN.md "Conventions", pixels).
    #[default]
    Jittered,
    /// The pixel centre every frame: no antialiasing, so two methods compared at the same
    /// setting differ only by their light transport, not by pixel-footprint noise.
    Centres,
}

impl PixelSampling {
    /// `Centres` when `centres`, else `Jittered` (the `pixel_centres` setting).
    pub fn from_centres(centres: bool) -> PixelSampling {
        if centres {
            PixelSampling::Centres
        } else {
            PixelSampling::Jittered
        }
    }
}

pub struct GBuffer {
    pub texels: Buffer<GBufferTexel>,
}

impl GBuffer {
    pub fn new(ctx: &Context, scene: &GpuScene) -> GpuResult<GBuffer> {
        Ok(GBuffer {
            texels: Buffer::zeroed(ctx, "GBuffer", scene.pixel_count())?,
        })
    }
}

pub struct WriteGBuffer(Kernel);

impl WriteGBuffer {
    pub fn new(ctx: &Context) -> GpuResult<Self> {
        Ok(WriteGBuffer(Kernel::new(ctx, "write_gbuffer")?))
    }

    /// Frame `frame`: Halton point `frame` of the pixel's shifted sequence.
    pub fn record<'a>(
        &'a self,
        cmd: &mut Commands<'a>,
        scene: &'a GpuScene,
        gbuffer: &'a GBuffer,
        frame: u32,
        seed: u32,
        sampling: PixelSampling,
    ) -> GpuResult<()> {
        let mut bindings = scene.bindings();
        bindings.push(bind("GBuffer", &gbuffer.texels));
        let params = FrameParams {
            frame,
            seed,
            centred: u32::from(sampling == PixelSampling::Centres),
            _pad: 0,
        };
        self.0
            .dispatch(cmd, &bindings, &params, scene.image_workgroups())
    }
}
