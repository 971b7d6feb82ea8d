//! glsl/ir/accumulate_vpls_tiled.comp: every (pixel, VPL) pair of a frame, tile by tile, with
//! VPLs streamed through shared memory, added into the accumulation.

use std::ops::Range;

use bytemuck::{Pod, Zeroable};

use glam::Vec4;

use crate::gpu::{bind, Buffer, Commands, Context, GpuResult};
use crate::methods::accumulation::Accumulation;
use crate::methods::gbuffer::GBuffer;
use crate::methods::scene_kernel::SceneKernel;
use crate::scene::gpu::GpuScene;

use super::walk::Vpl;

/// VPL slots shaded per dispatch (8 chunks of 64).
pub const SLOTS_PER_DISPATCH: u32 = 512;

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct GatherParams {
    vpl_begin: u32,
    vpl_end: u32,
    g_clamp: f32,
    interleave: u32,
    weight: f32,
}

/// The GLSL layouts the structs above mirror (src/gpu/contracts.rs checks them).
#[cfg(test)]
pub(crate) const GPU_LAYOUTS: &[crate::gpu::contracts::GpuLayout] = {
    use crate::gpu::contracts::gpu_layout;
    &[gpu_layout!(GatherParams in ["accumulate_vpls_tiled"] {
        vpl_begin,
        vpl_end,
        g_clamp,
        interleave,
        weight,
    })]
};

pub struct AccumulateVpls(SceneKernel);

impl AccumulateVpls {
    pub fn new(ctx: &Context) -> GpuResult<Self> {
        Ok(AccumulateVpls(SceneKernel::new(
            ctx,
            "accumulate_vpls_tiled",
        )?))
    }

    /// Shades the VPL slots `slots` of `vpls`, each contribution times `weight`; `g_clamp` 0
    /// leaves the geometry term unclamped. With `interleave` 1 it adds into `accumulation`;
    /// above, it adds into `vpl_radiance` for the filter (the caller clears it per frame).
    #[allow(clippy::too_many_arguments)]
    pub fn record<'a>(
        &'a self,
        cmd: &mut Commands<'a>,
        scene: &'a GpuScene,
        gbuffer: &'a GBuffer,
        vpls: &'a Buffer<Vpl>,
        accumulation: &'a Accumulation,
        vpl_radiance: &'a Buffer<Vec4>,
        slots: Range<u32>,
        g_clamp: f32,
        interleave: u32,
        weight: f32,
    ) -> GpuResult<()> {
        let mut bindings = scene.bindings();
        bindings.push(bind("GBuffer", &gbuffer.texels));
        bindings.extend(accumulation.bindings());
        bindings.push(bind("Vpls", vpls));
        bindings.push(bind("VplRadiance", vpl_radiance));
        // One dispatch per SLOTS_PER_DISPATCH slots. On lavapipe (Mesa 22.3) this kernel's sums
        // came out deterministically short once one dispatch looped over 32 or more chunks
        // (4096 paths lost 6% of the image at 32 chunks, 63% unsplit; 24 chunks and fewer
        // matched the reference). The cause: gallivm breaks out of an invocation's loops once
        // they have run 65535 iterations together (LP_MAX_TGSI_LOOP_ITERATIONS; docs/DESIGN.md
        // "The loop budget"). Short dispatches also keep real GPUs under watchdog limits.
        // tests/ir.rs checks large slot counts against the reference.
        let kernel = self.0.get(scene.features)?;
        let mut begin = slots.start;
        while begin < slots.end {
            let end = slots.end.min(begin + SLOTS_PER_DISPATCH);
            let params = GatherParams {
                vpl_begin: begin,
                vpl_end: end,
                g_clamp,
                interleave: interleave.max(1),
                weight,
            };
            kernel.dispatch(cmd, &bindings, &params, scene.image_workgroups())?;
            begin = end;
        }
        Ok(())
    }
}
