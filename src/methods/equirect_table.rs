//! A sampling table over the scene's environment map, rebuilt on the GPU
//! (glsl/include/equirect_table.glsl reads it): glsl/shared/weigh_equirect_texels.comp weighs every
//! texel by (Y(Le) + offset) times its solid angle, then the prefix sums within each row and
//! over the row totals. Used by bundles (Tokuyoshi 12 Eq. 2's bundle directions, offset Lo)
//! and env's `latlong` strategy (light sampling, offset 0).

use bytemuck::{Pod, Zeroable};

use crate::gpu::prefix_sum::PrefixSum;
use crate::gpu::{bind, Binding, Buffer, Commands, Context, GpuResult, Kernel};
use crate::scene::gpu::GpuScene;

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct WeighParams {
    offset: f32,
}

/// The GLSL layouts the structs above mirror (src/gpu/contracts.rs checks them).
#[cfg(test)]
pub(crate) const GPU_LAYOUTS: &[crate::gpu::contracts::GpuLayout] = {
    use crate::gpu::contracts::gpu_layout;
    &[gpu_layout!(WeighParams in ["weigh_equirect_texels"] { offset })]
};

/// The kernel and the two scans that build the table.
struct Builder {
    weigh: Kernel,
    within_rows: PrefixSum,
    over_rows: PrefixSum,
    offset: f32,
    size: [u32; 2],
}

/// The table, or, for a scene without a map, placeholders for its bindings.
pub struct EquirectTable {
    builder: Option<Builder>,
    weights: Buffer<f32>,
    /// Per row, the inclusive scan of the texel weights.
    cdf: Buffer<f32>,
    row_totals: Buffer<f32>,
    /// The inclusive scan of the row totals.
    row_cdf: Buffer<f32>,
    total: Buffer<f32>,
}

impl EquirectTable {
    /// The table of `scene`'s map with `offset` added to every texel's luminance; placeholders
    /// when the scene has no map or `build` is false.
    pub fn new(ctx: &Context, scene: &GpuScene, offset: f32, build: bool) -> GpuResult<Self> {
        let size = scene.environment_size.filter(|_| build);
        let (texels, rows) = size.map_or((1, 1), |[w, h]| ((w * h) as usize, h as usize));
        let builder = match size {
            Some([w, h]) => Some(Builder {
                weigh: Kernel::new(ctx, "weigh_equirect_texels")?,
                within_rows: PrefixSum::new(ctx, w as usize, rows)?,
                over_rows: PrefixSum::new(ctx, rows, 1)?,
                offset,
                size: [w, h],
            }),
            None => None,
        };
        Ok(EquirectTable {
            builder,
            weights: Buffer::zeroed(ctx, "EquirectWeights", texels)?,
            cdf: Buffer::zeroed(ctx, "EquirectCdf", texels)?,
            row_totals: Buffer::zeroed(ctx, "equirect row totals", rows)?,
            row_cdf: Buffer::zeroed(ctx, "EquirectRowCdf", rows)?,
            total: Buffer::zeroed(ctx, "EquirectTotal", 1)?,
        })
    }

    /// Whether the table is built (the scene has a map and it was asked for).
    pub fn is_built(&self) -> bool {
        self.builder.is_some()
    }

    /// The table's bindings, for every kernel that includes equirect_table.glsl.
    pub fn bindings(&self) -> [Binding<'_>; 3] {
        [
            bind("EquirectCdf", &self.cdf),
            bind("EquirectRowCdf", &self.row_cdf),
            bind("EquirectTotal", &self.total),
        ]
    }

    /// Rebuilds the table from the map (nothing for placeholders).
    pub fn record<'a>(&'a self, cmd: &mut Commands<'a>, scene: &'a GpuScene) -> GpuResult<()> {
        let Some(b) = &self.builder else {
            return Ok(());
        };
        let mut bindings = scene.bindings();
        bindings.push(bind("EquirectWeights", &self.weights));
        let [w, h] = b.size;
        let params = WeighParams { offset: b.offset };
        b.weigh
            .dispatch_threads(cmd, &bindings, &params, [w, h, 1])?;
        b.within_rows
            .record(cmd, &self.weights, &self.cdf, &self.row_totals)?;
        b.over_rows
            .record(cmd, &self.row_totals, &self.row_cdf, &self.total)
    }
}
