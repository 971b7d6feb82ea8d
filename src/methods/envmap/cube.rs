//! The per-frame cube-map sampling table of method `env` (Lu 14 Section 3.3, Alg. 1 lines
//! 5-10), all on the GPU: glsl/envmap/weigh_env_cube.comp (each cube texel's conservative luminance
//! times its solid angle), the prefix sums within every face row and over each face's row
//! totals (glsl/include/env_cube.glsl reads them), and glsl/envmap/generate_env_samples.comp (the
//! frame's light samples per face, shared by every pixel).

use bytemuck::{Pod, Zeroable};

use crate::gpu::prefix_sum::PrefixSum;
use crate::gpu::{bind, Binding, Buffer, Commands, Context, GpuResult, Kernel};
use crate::sampling::cubemap::footprint_bound;
use crate::scene::gpu::GpuScene;

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct CubeParams {
    resolution: u32,
    first: u32,
    count: u32,
    planned: u32,
}

/// Map texels one weigh_env_cube invocation searches per dispatch: half lavapipe's loop budget
/// of 65535 iterations (the rest of the kernel loops at most 8 + 12 times: the footprint's
/// walk and cube_texel_solid_angle).
const FOOTPRINT_TEXELS_PER_DISPATCH: u32 = 32768;

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct SampleParams {
    resolution: u32,
    per_face: u32,
    first: u32,
    seed: u32,
    set: u32,
    window: u32,
}

/// The GLSL layouts the structs above mirror (src/gpu/contracts.rs checks them).
#[cfg(test)]
pub(crate) const GPU_LAYOUTS: &[crate::gpu::contracts::GpuLayout] = {
    use crate::gpu::contracts::gpu_layout;
    &[
        gpu_layout!(CubeParams in ["weigh_env_cube"] { resolution, first, count, planned }),
        gpu_layout!(SampleParams in ["generate_env_samples"] {
            resolution,
            per_face,
            first,
            seed,
            set,
            window,
        }),
    ]
};

pub struct CubeTable {
    weigh: Kernel,
    generate: Kernel,
    within_rows: PrefixSum,
    over_rows: PrefixSum,
    /// R: texels along a face's side.
    pub resolution: u32,
    /// Light samples per face, set, frame and window (what one pixel may take).
    pub per_face: u32,
    /// Windows of `per_face` samples per face and set; each pixel reads one (1: every pixel
    /// shares one set, Lu's).
    pub windows: u32,
    /// Independent sample sets (alpha draws its two steps from two).
    pub sets: u32,
    pub weights: Buffer<f32>,
    row_cdf: Buffer<f32>,
    row_totals: Buffer<f32>,
    face_cdf: Buffer<f32>,
    pub face_totals: Buffer<f32>,
    pub samples: Buffer<[f32; 4]>,
}

impl CubeTable {
    pub fn new(
        ctx: &Context,
        resolution: u32,
        per_face: u32,
        sets: u32,
        windows: u32,
    ) -> GpuResult<Self> {
        let r = resolution.max(1) as usize;
        let per_face = per_face.max(1);
        let sets = sets.max(1);
        let windows = windows.max(1);
        Ok(CubeTable {
            weigh: Kernel::new(ctx, "weigh_env_cube")?,
            generate: Kernel::new(ctx, "generate_env_samples")?,
            within_rows: PrefixSum::new(ctx, r, 6 * r)?,
            over_rows: PrefixSum::new(ctx, r, 6)?,
            resolution: r as u32,
            per_face,
            windows,
            sets,
            weights: Buffer::zeroed(ctx, "CubeWeights", 6 * r * r)?,
            row_cdf: Buffer::zeroed(ctx, "CubeRowCdf", 6 * r * r)?,
            row_totals: Buffer::zeroed(ctx, "cube row totals", 6 * r)?,
            face_cdf: Buffer::zeroed(ctx, "CubeFaceCdf", 6 * r)?,
            face_totals: Buffer::zeroed(ctx, "CubeFaceTotals", 6)?,
            samples: Buffer::zeroed(ctx, "EnvSamples", 6 * (sets * per_face * windows) as usize)?,
        })
    }

    /// The table's bindings, for every kernel that includes env_cube.glsl.
    pub fn bindings(&self) -> [Binding<'_>; 3] {
        [
            bind("CubeRowCdf", &self.row_cdf),
            bind("CubeFaceCdf", &self.face_cdf),
            bind("CubeFaceTotals", &self.face_totals),
        ]
    }

    /// Pass "cube map": the weights from the scene's map, the footprints' search split over
    /// as many dispatches as the largest footprint needs (`footprint_bound`; one for the
    /// shipped maps at the default resolution).
    pub fn record_weights<'a>(
        &'a self,
        cmd: &mut Commands<'a>,
        scene: &'a GpuScene,
    ) -> GpuResult<()> {
        let mut bindings = scene.bindings();
        bindings.push(bind("CubeWeights", &self.weights));
        let r = self.resolution;
        let [w, h] = scene.environment_size.unwrap_or([1, 1]);
        let count = FOOTPRINT_TEXELS_PER_DISPATCH;
        let dispatches = footprint_bound(w, h, r).div_ceil(count as u64).max(1) as u32;
        for d in 0..dispatches {
            let params = CubeParams {
                resolution: r,
                first: d * count,
                count,
                planned: dispatches.saturating_mul(count),
            };
            self.weigh
                .dispatch_threads(cmd, &bindings, &params, [r, r, 6])?;
        }
        Ok(())
    }

    /// Pass "cdf": the scans of the weights.
    pub fn record_cdf<'a>(&'a self, cmd: &mut Commands<'a>) -> GpuResult<()> {
        self.within_rows
            .record(cmd, &self.weights, &self.row_cdf, &self.row_totals)?;
        self.over_rows
            .record(cmd, &self.row_totals, &self.face_cdf, &self.face_totals)
    }

    /// Pass "light samples": `per_face` samples per face and window of sample set `set`, each
    /// window a scrambled Halton sequence from index `first`, window 0 scrambled by `seed`,
    /// the others each by their own hash of it.
    pub fn record_samples<'a>(
        &'a self,
        cmd: &mut Commands<'a>,
        set: u32,
        first: u32,
        seed: u32,
    ) -> GpuResult<()> {
        let mut bindings: Vec<Binding<'_>> = self.bindings().into_iter().collect();
        bindings.push(bind("EnvSamples", &self.samples));
        let params = SampleParams {
            resolution: self.resolution,
            per_face: self.per_face * self.windows,
            first,
            seed,
            set: set.min(self.sets - 1),
            window: self.per_face,
        };
        self.generate.dispatch_threads(
            cmd,
            &bindings,
            &params,
            [self.per_face * self.windows, 6, 1],
        )
    }
}
