//! glsl/bir/estimate_light_contributions.comp and glsl/bir/build_light_cdf.comp: bir's many-light
//! sampling (Segovia 06 Section 4.1): each light's contribution to what the camera sees,
//! measured once per render at `SAMPLES` camera points and one bounce beyond, summed per light by the GPU
//! prefix sum (one row per light), and the table that starts light paths in proportion to it
//! plus a floor, so no light that can contribute has zero probability.

use bytemuck::{Pod, Zeroable};

use crate::gpu::prefix_sum::PrefixSum;
use crate::gpu::{bind, Buffer, Commands, Context, GpuError, GpuResult, Kernel};
use crate::methods::gbuffer::GBuffer;
use crate::methods::scene_kernel::SceneKernel;
use crate::scene::gpu::{GpuScene, LightEntry};

/// Camera samples the light contributions are measured at.
pub const SAMPLES: u32 = 1024;

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct ContributionParams {
    samples: u32,
    entries: u32,
    seed: u32,
    pixels: u32,
}

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct CdfParams {
    entries: u32,
    floor_fraction: f32,
    first: u32,
    count: u32,
    phase: u32,
}

/// The GLSL layouts the structs above mirror (src/gpu/contracts.rs checks them).
#[cfg(test)]
pub(crate) const GPU_LAYOUTS: &[crate::gpu::contracts::GpuLayout] = {
    use crate::gpu::contracts::gpu_layout;
    &[
        gpu_layout!(ContributionParams in ["estimate_light_contributions"] {
            samples,
            entries,
            seed,
            pixels,
        }),
        gpu_layout!(CdfParams in ["build_light_cdf"] { entries, floor_fraction, first, count, phase }),
    ]
};

/// Lights one build_light_cdf dispatch walks: half lavapipe's loop budget of 65535 iterations
/// an invocation.
const LIGHTS_PER_DISPATCH: u32 = 32768;

pub struct LightCdf {
    estimate: SceneKernel,
    build: Kernel,
    entries: u32,
    contributions: Buffer<f32>,
    sums: Buffer<f32>,
    totals: Buffer<f32>,
    scan: PrefixSum,
    /// build_light_cdf's sums carried from one dispatch to the next (CdfState).
    state: Buffer<[u32; 4]>,
    /// The camera-driven light table, laid out as the scene's LightEntries.
    pub table: Buffer<LightEntry>,
    /// Lights build_light_cdf walks a dispatch (LIGHTS_PER_DISPATCH; tests lower it).
    pub lights_per_dispatch: u32,
}

impl LightCdf {
    pub fn new(ctx: &Context, scene: &GpuScene) -> GpuResult<Self> {
        let entries = scene.light_entries.len().max(1) as u32;
        let n = entries as usize * SAMPLES as usize;
        // The contributions, one float per light and camera sample, in one buffer, and one
        // row of workgroups per light: refused here, before any frame, in the setting's words.
        let bytes = n as u64 * size_of::<f32>() as u64;
        let limit = ctx.info().max_storage_buffer_range;
        let rows = ctx.info().max_workgroup_count[1] as u64;
        let most = (limit / (SAMPLES as u64 * size_of::<f32>() as u64)).min(rows);
        if entries as u64 > most {
            let why = if bytes > limit {
                format!(
                    "would take {bytes} bytes in one buffer, over this device's \
                     maxStorageBufferRange of {limit} bytes"
                )
            } else {
                format!("would take more than this device's {rows} workgroups down a dispatch")
            };
            return Err(GpuError::DoesNotFit(format!(
                "bir: light_cdf = true (--light-cdf): measuring each of the scene's {entries} \
                 lights at {SAMPLES} camera points {why} (`irad info`); at most {most} lights \
                 fit: set light_cdf = false (--light-cdf=false) to choose lights by power"
            )));
        }
        Ok(LightCdf {
            estimate: SceneKernel::new(ctx, "estimate_light_contributions")?,
            build: Kernel::new(ctx, "build_light_cdf")?,
            entries,
            contributions: Buffer::zeroed(ctx, "Contributions", n)?,
            sums: Buffer::zeroed(ctx, "light contribution sums", n)?,
            totals: Buffer::zeroed(ctx, "RowTotals", entries as usize)?,
            scan: PrefixSum::new(ctx, SAMPLES as usize, entries as usize)?,
            state: Buffer::zeroed(ctx, "CdfState", 1)?,
            table: Buffer::zeroed(ctx, "CameraLightEntries", entries as usize)?,
            lights_per_dispatch: LIGHTS_PER_DISPATCH,
        })
    }

    /// Measures this frame's contributions on `gbuffer` and rebuilds `table`.
    pub fn record<'a>(
        &'a self,
        cmd: &mut Commands<'a>,
        scene: &'a GpuScene,
        gbuffer: &'a GBuffer,
        seed: u32,
        floor_fraction: f32,
    ) -> GpuResult<()> {
        let mut bindings = scene.bindings();
        bindings.push(bind("GBuffer", &gbuffer.texels));
        bindings.push(bind("Contributions", &self.contributions));
        let params = ContributionParams {
            samples: SAMPLES,
            entries: self.entries,
            seed,
            pixels: scene.pixel_count() as u32,
        };
        self.estimate.get(scene.features)?.dispatch(
            cmd,
            &bindings,
            &params,
            [SAMPLES.div_ceil(64), self.entries, 1],
        )?;
        self.scan
            .record(cmd, &self.contributions, &self.sums, &self.totals)?;
        let mut bindings = scene.bindings();
        bindings.push(bind("RowTotals", &self.totals));
        bindings.push(bind("CdfState", &self.state));
        bindings.push(bind("CameraLightEntries", &self.table));
        // Two sequential walks over the lights, each in ranges a dispatch (one each for fewer
        // than LIGHTS_PER_DISPATCH lights).
        for phase in 0..2 {
            let count = self.lights_per_dispatch.clamp(1, LIGHTS_PER_DISPATCH);
            for first in (0..self.entries).step_by(count as usize) {
                let params = CdfParams {
                    entries: self.entries,
                    floor_fraction,
                    first,
                    count,
                    phase,
                };
                self.build.dispatch(cmd, &bindings, &params, [1, 1, 1])?;
            }
        }
        Ok(())
    }
}
