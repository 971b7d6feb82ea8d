//! glsl/bir/estimate_vpl_power.comp and glsl/bir/resample_vpls.comp: bir's resampling (Segovia 06
//! Sections 3.2, 4.2): each candidate's power to the camera from M camera points, a CDF over
//! the candidates by the GPU prefix sum (two rows: the powers and the non-empty flags, for the
//! uniform floor), and N' systematic draws, each a VPL of power P_c / (N' q_c).

use bytemuck::{Pod, Zeroable};

use crate::gpu::prefix_sum::PrefixSum;
use crate::gpu::{bind, Buffer, Commands, Context, GpuResult, Kernel};
use crate::methods::gbuffer::GBuffer;
use crate::methods::ir::walk::Vpl;
use crate::methods::scene_kernel::SceneKernel;
use crate::scene::gpu::GpuScene;

use super::reverse::{pieces, RAYS_PER_DISPATCH};

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct PowerParams {
    count: u32,
    source_begin: u32,
    offset: u32,
    row_length: u32,
    samples: u32,
    seed: u32,
    pixels: u32,
    scale: f32,
    sample_begin: u32,
    sample_end: u32,
}

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct ResampleParams {
    draws: u32,
    kept_offset: u32,
    candidates: u32,
    standard: u32,
    standard_begin: u32,
    unused: f32,
    floor_fraction: f32,
    seed: u32,
}

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct SideParams {
    candidates: u32,
    standard: u32,
    min_weight: f32,
}

/// The GLSL layouts the structs above mirror (src/gpu/contracts.rs checks them).
#[cfg(test)]
pub(crate) const GPU_LAYOUTS: &[crate::gpu::contracts::GpuLayout] = {
    use crate::gpu::contracts::gpu_layout;
    &[
        gpu_layout!(PowerParams in ["estimate_vpl_power"] {
            count,
            source_begin,
            offset,
            row_length,
            samples,
            seed,
            pixels,
            scale,
            sample_begin,
            sample_end,
        }),
        gpu_layout!(ResampleParams in ["resample_vpls"] {
            draws,
            kept_offset,
            candidates,
            standard,
            standard_begin,
            unused,
            floor_fraction,
            seed,
        }),
        gpu_layout!(SideParams in ["update_side_weights"] { candidates, standard, min_weight }),
    ]
};

/// The per-batch buffers of the resampling: weights and their scan, two rows of `candidates`.
pub struct ResampleBuffers {
    pub candidates: u32,
    pub weights: Buffer<f32>,
    pub scanned: Buffer<f32>,
    pub totals: Buffer<f32>,
    pub scan: PrefixSum,
    /// Draws kept from the standard and the reverse side, over the whole render.
    pub stats: Buffer<u32>,
    /// The sides' weights, the batches the standard side won and the batches counted
    /// (update_side_weights.comp).
    pub side: Buffer<[f32; 4]>,
}

impl ResampleBuffers {
    /// `weights`: the sides' starting weights (standard, reverse).
    pub fn new(ctx: &Context, candidates: u32, weights: [f32; 2]) -> GpuResult<Self> {
        let n = 2 * candidates.max(1) as usize;
        Ok(ResampleBuffers {
            candidates: candidates.max(1),
            weights: Buffer::zeroed(ctx, "Weights", n)?,
            scanned: Buffer::zeroed(ctx, "Scanned", n)?,
            totals: Buffer::zeroed(ctx, "RowTotals", 2)?,
            scan: PrefixSum::new(ctx, candidates.max(1) as usize, 2)?,
            stats: Buffer::zeroed(ctx, "ResampleStats", 2)?,
            side: Buffer::from_slice(ctx, "SideWeights", &[[weights[0], weights[1], 0.0, 0.0]])?,
        })
    }
}

pub struct EstimateVplPower(SceneKernel);

impl EstimateVplPower {
    pub fn new(ctx: &Context) -> GpuResult<Self> {
        Ok(EstimateVplPower(SceneKernel::new(
            ctx,
            "estimate_vpl_power",
        )?))
    }

    /// Weights candidates `offset..offset + count` from slots `source_begin..` of `source`.
    #[allow(clippy::too_many_arguments)]
    pub fn record<'a>(
        &'a self,
        cmd: &mut Commands<'a>,
        scene: &'a GpuScene,
        gbuffer: &'a GBuffer,
        source: &'a Buffer<Vpl>,
        source_begin: u32,
        count: u32,
        offset: u32,
        buffers: &'a ResampleBuffers,
        samples: u32,
        seed: u32,
        scale: f32,
    ) -> GpuResult<()> {
        if count == 0 {
            return Ok(());
        }
        let mut bindings = scene.bindings();
        bindings.push(bind("GBuffer", &gbuffer.texels));
        bindings.push(bind("Vpls", source));
        bindings.push(bind("Weights", &buffers.weights));
        let mut params = PowerParams {
            count,
            source_begin,
            offset,
            row_length: buffers.candidates,
            samples: samples.max(1),
            seed,
            pixels: scene.pixel_count() as u32,
            scale,
            sample_begin: 0,
            sample_end: 0,
        };
        // A shadow ray per camera point: RAYS_PER_DISPATCH of them per dispatch.
        let kernel = self.0.get(scene.features)?;
        for (begin, end) in pieces(params.samples, RAYS_PER_DISPATCH) {
            params.sample_begin = begin;
            params.sample_end = end;
            kernel.dispatch(cmd, &bindings, &params, [count.div_ceil(64), 1, 1])?;
        }
        Ok(())
    }
}

/// Where a batch's candidates come from.
pub struct Candidates<'a> {
    pub standard: &'a Buffer<Vpl>,
    pub standard_begin: u32,
    pub standard_count: u32,
    pub reverse: &'a Buffer<Vpl>,
}

pub struct ResampleVpls(Kernel);

impl ResampleVpls {
    pub fn new(ctx: &Context) -> GpuResult<Self> {
        Ok(ResampleVpls(Kernel::new(ctx, "resample_vpls")?))
    }

    /// Scans the weights and writes `draws` VPLs into `kept` from `kept_offset`.
    #[allow(clippy::too_many_arguments)]
    pub fn record<'a>(
        &'a self,
        cmd: &mut Commands<'a>,
        candidates: &Candidates<'a>,
        buffers: &'a ResampleBuffers,
        kept: &'a Buffer<Vpl>,
        kept_offset: u32,
        draws: u32,
        floor_fraction: f32,
        seed: u32,
    ) -> GpuResult<()> {
        buffers
            .scan
            .record(cmd, &buffers.weights, &buffers.scanned, &buffers.totals)?;
        let bindings = vec![
            bind("Vpls", candidates.standard),
            bind("ReverseVpls", candidates.reverse),
            bind("Weights", &buffers.weights),
            bind("KeptVpls", kept),
            bind("Scanned", &buffers.scanned),
            bind("RowTotals", &buffers.totals),
            bind("ResampleStats", &buffers.stats),
            bind("SideWeights", &buffers.side),
        ];
        let params = ResampleParams {
            draws,
            kept_offset,
            candidates: buffers.candidates,
            standard: candidates.standard_count,
            standard_begin: candidates.standard_begin,
            unused: 0.0,
            floor_fraction,
            seed,
        };
        self.0
            .dispatch(cmd, &bindings, &params, [draws.div_ceil(64), 1, 1])
    }
}

/// glsl/bir/update_side_weights.comp: after a batch, `both`'s standard weight follows the
/// fraction of the batches so far in which the standard candidates brought more camera power
/// than the reverse ones, sharpened and clamped to [min_weight, 1 - min_weight].
pub struct UpdateSideWeights(Kernel);

impl UpdateSideWeights {
    pub fn new(ctx: &Context) -> GpuResult<Self> {
        Ok(UpdateSideWeights(Kernel::new(ctx, "update_side_weights")?))
    }

    pub fn record<'a>(
        &'a self,
        cmd: &mut Commands<'a>,
        buffers: &'a ResampleBuffers,
        standard: u32,
        min_weight: f32,
    ) -> GpuResult<()> {
        let bindings = vec![
            bind("Scanned", &buffers.scanned),
            bind("SideWeights", &buffers.side),
        ];
        let params = SideParams {
            candidates: buffers.candidates,
            standard,
            min_weight,
        };
        self.0.dispatch(cmd, &bindings, &params, [1, 1, 1])
    }
}
