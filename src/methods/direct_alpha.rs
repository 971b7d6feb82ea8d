//! glsl/shared/shade_direct_alpha.comp: the reference's direct light (`--max-depth 1`) with Lu 14
//! Chapter 5's per-pixel split between light and BSDF sampling (`--alpha-frames M`): the first
//! M frames take one sample of each and estimate alpha (Eq. 5.4-5.5) into a per-pixel state;
//! later frames split two samples by it. The per-pixel state also yields the alpha map.

use bytemuck::{Pod, Zeroable};

use crate::gpu::{bind, Buffer, Commands, Context, GpuResult, Kernel};
use crate::scene::gpu::GpuScene;

use super::accumulation::Accumulation;
use super::gbuffer::GBuffer;

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct AlphaParams {
    frame: u32,
    seed: u32,
    estimation_frames: u32,
}

/// The GLSL layouts the structs above mirror (src/gpu/contracts.rs checks them).
#[cfg(test)]
pub(crate) const GPU_LAYOUTS: &[crate::gpu::contracts::GpuLayout] = {
    use crate::gpu::contracts::gpu_layout;
    &[gpu_layout!(AlphaParams in ["shade_direct_alpha"] { frame, seed, estimation_frames })]
};

pub struct ShadeDirectAlpha(Kernel);

/// Per pixel: Eq. 5.5's two sums (x, y), the frames from M on that saw a surface (z) and
/// their alphas summed (w).
pub type AlphaState = Buffer<[f32; 4]>;

impl ShadeDirectAlpha {
    pub fn new(ctx: &Context) -> GpuResult<Self> {
        Ok(ShadeDirectAlpha(Kernel::new(ctx, "shade_direct_alpha")?))
    }

    pub fn state(ctx: &Context, scene: &GpuScene) -> GpuResult<AlphaState> {
        Buffer::zeroed(ctx, "DirectAlphaState", scene.pixel_count())
    }

    #[allow(clippy::too_many_arguments)]
    pub fn record<'a>(
        &'a self,
        cmd: &mut Commands<'a>,
        scene: &'a GpuScene,
        gbuffer: &'a GBuffer,
        accumulation: &'a Accumulation,
        state: &'a AlphaState,
        frame: u32,
        seed: u32,
        estimation_frames: u32,
    ) -> GpuResult<()> {
        let mut bindings = scene.bindings();
        bindings.push(bind("GBuffer", &gbuffer.texels));
        bindings.extend(accumulation.bindings());
        bindings.push(bind("DirectAlphaState", state));
        let params = AlphaParams {
            frame,
            seed,
            estimation_frames,
        };
        self.0
            .dispatch(cmd, &bindings, &params, scene.image_workgroups())
    }
}
