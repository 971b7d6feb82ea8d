//! The density the global ray bundles' directions are drawn from (Tokuyoshi 12 Section 3.3,
//! glsl/include/bundle_directions.glsl): uniform on the sphere, or, under an environment map,
//! Eq. 2's p_r proportional to Le(w) + Le(-w) + 2 Lo, tabulated on the GPU every frame
//! (glsl/weigh_bundle_directions.comp, then the prefix sums: within each row of the map, and
//! over the rows' totals), so a map that changes per frame costs no CPU work.

use bytemuck::{Pod, Zeroable};

use crate::gpu::prefix_sum::PrefixSum;
use crate::gpu::{bind, Binding, Buffer, Commands, Context, GpuResult, Kernel};
use crate::scene::gpu::GpuScene;

/// Where the bundle directions come from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DirectionDensity {
    /// Uniform on the sphere: p_r = 1 / (2 pi) (the paper's choice indoors and for dynamic
    /// maps).
    Uniform,
    /// Eq. 2 over the scene's environment map, with an offset Lo (luminance) for the indirect
    /// light the map does not show.
    Environment,
}

impl DirectionDensity {
    pub fn name(self) -> &'static str {
        match self {
            DirectionDensity::Uniform => "uniform",
            DirectionDensity::Environment => "environment",
        }
    }
}

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct WeighParams {
    offset: f32,
}

/// The kernel and the two scans that build the table.
struct Builder {
    weigh: Kernel,
    within_rows: PrefixSum,
    over_rows: PrefixSum,
}

/// The table (or, for uniform directions, placeholders for its bindings).
pub struct BundleDirections {
    density: DirectionDensity,
    offset: f32,
    builder: Option<Builder>,
    weights: Buffer<f32>,
    /// Per row, the inclusive scan of the texel weights.
    cdf: Buffer<f32>,
    row_totals: Buffer<f32>,
    /// The inclusive scan of the row totals.
    row_cdf: Buffer<f32>,
    total: Buffer<f32>,
    env_size: [u32; 2],
}

impl BundleDirections {
    /// `density` Environment on a scene without a map is uniform; `offset` is Lo.
    pub fn new(
        ctx: &Context,
        scene: &GpuScene,
        density: DirectionDensity,
        offset: f32,
    ) -> GpuResult<Self> {
        let [w, h] = scene.environment_size.unwrap_or([0, 0]);
        let density = if scene.environment_size.is_none() {
            DirectionDensity::Uniform
        } else {
            density
        };
        let (texels, rows) = match density {
            DirectionDensity::Uniform => (1, 1),
            DirectionDensity::Environment => ((w * h) as usize, h as usize),
        };
        let builder = match density {
            DirectionDensity::Uniform => None,
            DirectionDensity::Environment => Some(Builder {
                weigh: Kernel::new(ctx, "weigh_bundle_directions")?,
                within_rows: PrefixSum::new(ctx, w as usize, rows)?,
                over_rows: PrefixSum::new(ctx, rows, 1)?,
            }),
        };
        Ok(BundleDirections {
            density,
            offset,
            builder,
            weights: Buffer::zeroed(ctx, "BundleDirectionWeights", texels)?,
            cdf: Buffer::zeroed(ctx, "BundleDirectionCdf", texels)?,
            row_totals: Buffer::zeroed(ctx, "bundle direction row totals", rows)?,
            row_cdf: Buffer::zeroed(ctx, "BundleRowCdf", rows)?,
            total: Buffer::zeroed(ctx, "BundleDirectionTotal", 1)?,
            env_size: [w, h],
        })
    }

    pub fn density(&self) -> DirectionDensity {
        self.density
    }

    /// BUNDLE_DIRECTIONS_UNIFORM or _ENVIRONMENT of bundle_directions.glsl.
    pub fn mode_code(&self) -> u32 {
        match self.density {
            DirectionDensity::Uniform => 0,
            DirectionDensity::Environment => 1,
        }
    }

    /// The table's bindings, for every kernel that includes bundle_directions.glsl.
    pub fn bindings(&self) -> [Binding<'_>; 3] {
        [
            bind("BundleDirectionCdf", &self.cdf),
            bind("BundleRowCdf", &self.row_cdf),
            bind("BundleDirectionTotal", &self.total),
        ]
    }

    /// Rebuilds the table from the map (nothing for uniform directions).
    pub fn record<'a>(&'a self, cmd: &mut Commands<'a>, scene: &'a GpuScene) -> GpuResult<()> {
        let Some(b) = &self.builder else {
            return Ok(());
        };
        let mut bindings = scene.bindings();
        bindings.push(bind("BundleDirectionWeights", &self.weights));
        let [w, h] = self.env_size;
        let params = WeighParams {
            offset: self.offset,
        };
        b.weigh
            .dispatch_threads(cmd, &bindings, &params, [w, h, 1])?;
        b.within_rows
            .record(cmd, &self.weights, &self.cdf, &self.row_totals)?;
        b.over_rows
            .record(cmd, &self.row_totals, &self.row_cdf, &self.total)
    }
}
