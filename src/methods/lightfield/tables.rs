//! The light-field luminaire's sampling tables, built on the GPU with the scan kernels (Lu 14
//! Section 4.5), and rebuilt whenever the images change:
//! glsl/lightfield/weigh_luminaire_columns.comp (each texel's luminance, column by column), the prefix sum
//! over every column (the conditional CDFs in t, Eq. 4.10, and the column totals), the prefix
//! sum over each image's column totals (the marginal CDF in s, and the image totals),
//! glsl/lightfield/transpose_luminaire_columns.comp, and the prefix sum along every row of the transposed
//! column CDFs (the summed-area table). src/sampling/restricted.rs is the f64 mirror. A
//! luminaire with a sequence of atlases keeps them all on the GPU; frame f copies atlas
//! f mod n into the live texels and rebuilds every table from them (`record_frame`).

use bytemuck::{Pod, Zeroable};
use glam::Vec4;

use crate::gpu::prefix_sum::PrefixSum;
use crate::gpu::{bind, Buffer, Commands, Context, GpuBuffer, GpuResult, Kernel};
use crate::methods::rebuild::TableRebuild;
use crate::scene::luminaire::Luminaire;

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct TableParams {
    width: u32,
    height: u32,
    images: u32,
}

pub struct LuminaireTables {
    weigh: Kernel,
    transpose: Kernel,
    over_columns: PrefixSum,
    over_column_totals: PrefixSum,
    over_rows: PrefixSum,
    params: TableParams,
    /// The images' RGB texels (image m, row t, column s); .w unused.
    pub texels: Buffer<Vec4>,
    /// A sequence's every atlas, one after another (None for a still luminaire).
    sequence: Option<(Buffer<Vec4>, u32)>,
    columns: Buffer<f32>,
    /// Per image and column, the inclusive scan over t: (m, s, t).
    pub column_cdf: Buffer<f32>,
    pub column_totals: Buffer<f32>,
    /// Per image, the inclusive scan of the column totals: (m, s).
    pub marginal_cdf: Buffer<f32>,
    pub image_totals: Buffer<f32>,
    rows: Buffer<f32>,
    /// Per image, the inclusive summed-area table: (m, t, s) holds the integral over
    /// [0, s + 1] x [0, t + 1] in texel units.
    pub sat: Buffer<f32>,
    row_totals: Buffer<f32>,
}

impl LuminaireTables {
    pub fn new(ctx: &Context, luminaire: &Luminaire) -> GpuResult<Self> {
        let [rs, rt] = luminaire.geometry.resolution;
        let m = luminaire.images.len();
        let n = m * rs * rt;
        let texels_of = |images: &[Vec<glam::Vec3>]| -> Vec<Vec4> {
            images
                .iter()
                .flat_map(|im| im.iter().map(|c| c.extend(0.0)))
                .collect()
        };
        let texels = texels_of(&luminaire.images);
        let sequence = if luminaire.sequence.is_empty() {
            None
        } else {
            let all: Vec<Vec4> = luminaire
                .sequence
                .iter()
                .flat_map(|images| texels_of(images))
                .collect();
            Some((
                Buffer::from_slice(ctx, "luminaire atlases", &all)?,
                luminaire.sequence.len() as u32,
            ))
        };
        Ok(LuminaireTables {
            weigh: Kernel::new(ctx, "weigh_luminaire_columns")?,
            transpose: Kernel::new(ctx, "transpose_luminaire_columns")?,
            over_columns: PrefixSum::new(ctx, rt, m * rs)?,
            over_column_totals: PrefixSum::new(ctx, rs, m)?,
            over_rows: PrefixSum::new(ctx, rs, m * rt)?,
            params: TableParams {
                width: rs as u32,
                height: rt as u32,
                images: m as u32,
            },
            texels: Buffer::from_slice(ctx, "LuminaireTexels", &texels)?,
            sequence,
            columns: Buffer::zeroed(ctx, "ColumnValues", n)?,
            column_cdf: Buffer::zeroed(ctx, "ColumnCdf", n)?,
            column_totals: Buffer::zeroed(ctx, "luminaire column totals", m * rs)?,
            marginal_cdf: Buffer::zeroed(ctx, "MarginalCdf", m * rs)?,
            image_totals: Buffer::zeroed(ctx, "luminaire image totals", m)?,
            rows: Buffer::zeroed(ctx, "RowValues", n)?,
            sat: Buffer::zeroed(ctx, "LuminaireSat", n)?,
            row_totals: Buffer::zeroed(ctx, "luminaire row totals", m * rt)?,
        })
    }

    /// Whether the images change from frame to frame.
    pub fn is_sequence(&self) -> bool {
        self.sequence.is_some()
    }

    /// What frame `frame` needs: for a sequence, pass "luminaire frame" (atlas frame mod n
    /// copied into `texels`) and pass "luminaire tables"; for a still luminaire, the tables
    /// when `rebuild` says (at frame 0 only by default).
    pub fn record_frame<'a>(
        &'a self,
        cmd: &mut Commands<'a>,
        frame: u32,
        rebuild: TableRebuild,
    ) -> GpuResult<()> {
        if let Some((atlases, count)) = &self.sequence {
            let bytes = self.texels.byte_size();
            let k = (frame % count) as u64;
            cmd.pass("luminaire frame", |cmd| {
                cmd.copy_region(atlases, k * bytes, &self.texels, bytes);
                Ok(())
            })?;
        }
        if !rebuild.due(frame, self.is_sequence()) {
            return Ok(());
        }
        cmd.pass("luminaire tables", |cmd| self.record(cmd))
    }

    /// Every table from `texels`.
    pub fn record<'a>(&'a self, cmd: &mut Commands<'a>) -> GpuResult<()> {
        let p = self.params;
        let threads = [p.width, p.height, p.images];
        self.weigh.dispatch_threads(
            cmd,
            &[
                bind("LuminaireTexels", &self.texels),
                bind("ColumnValues", &self.columns),
            ],
            &p,
            threads,
        )?;
        self.over_columns
            .record(cmd, &self.columns, &self.column_cdf, &self.column_totals)?;
        self.over_column_totals.record(
            cmd,
            &self.column_totals,
            &self.marginal_cdf,
            &self.image_totals,
        )?;
        self.transpose.dispatch_threads(
            cmd,
            &[
                bind("ColumnCdf", &self.column_cdf),
                bind("RowValues", &self.rows),
            ],
            &p,
            threads,
        )?;
        self.over_rows
            .record(cmd, &self.rows, &self.sat, &self.row_totals)
    }
}

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct DrawParams {
    window: [f32; 4],
    m: u32,
    width: u32,
    height: u32,
    count: u32,
    seed: u32,
    search: u32,
    /// The block's size rounds up to its vec4's alignment.
    pad: [u32; 2],
}

/// The GLSL layouts the structs above mirror (src/gpu/contracts.rs checks them).
#[cfg(test)]
pub(crate) const GPU_LAYOUTS: &[crate::gpu::contracts::GpuLayout] = {
    use crate::gpu::contracts::gpu_layout;
    &[
        gpu_layout!(TableParams in ["weigh_luminaire_columns", "transpose_luminaire_columns"] {
            width,
            height,
            images,
        }),
        gpu_layout!(DrawParams in ["draw_luminaire_samples"] {
            window,
            m,
            width,
            height,
            count,
            seed,
            search,
            pad => pad,
        }),
    ]
};

/// glsl/lightfield/draw_luminaire_samples.comp: the restricted sampler of glsl/include/
/// luminaire_tables.glsl on its own, for its tests: `count` draws in one image's window, each
/// (s, t, realised pdf, search steps).
pub struct RestrictedDraws {
    kernel: Kernel,
    pub draws: Buffer<[f32; 4]>,
    count: u32,
}

impl RestrictedDraws {
    pub fn new(ctx: &Context, count: u32) -> GpuResult<Self> {
        Ok(RestrictedDraws {
            kernel: Kernel::new(ctx, "draw_luminaire_samples")?,
            draws: Buffer::zeroed(ctx, "LuminaireDraws", count.max(1) as usize)?,
            count,
        })
    }

    /// Draws in image `m`'s window (s0, s1, t0, t1) (texel units); `secant` picks Lu's
    /// modified secant search over binary search.
    pub fn record<'a>(
        &'a self,
        cmd: &mut Commands<'a>,
        tables: &'a LuminaireTables,
        m: u32,
        window: [f32; 4],
        secant: bool,
        seed: u32,
    ) -> GpuResult<()> {
        let params = DrawParams {
            window,
            m,
            width: tables.params.width,
            height: tables.params.height,
            count: self.count,
            seed,
            search: secant as u32,
            pad: [0; 2],
        };
        self.kernel.dispatch_threads(
            cmd,
            &[
                bind("LuminaireTexels", &tables.texels),
                bind("ColumnCdf", &tables.column_cdf),
                bind("LuminaireSat", &tables.sat),
                bind("LuminaireDraws", &self.draws),
            ],
            &params,
            [self.count, 1, 1],
        )
    }
}
