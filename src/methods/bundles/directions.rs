//! The density the global ray bundles' directions are drawn from (Tokuyoshi 12 Section 3.3,
//! glsl/include/bundle_directions.glsl): uniform on the sphere, or, under an environment map,
//! Eq. 2's p_r proportional to Le(w) + Le(-w) + 2 Lo, from the equirectangular table built with
//! offset Lo every frame on the GPU (methods::equirect_table), so a map that changes per frame
//! costs no CPU work.

use crate::gpu::{Binding, Commands, Context, GpuResult};
use crate::methods::equirect_table::EquirectTable;
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

crate::methods::settings::named_choices!(DirectionDensity {
    Uniform => "uniform",
    Environment => "environment",
});

/// The density and its table (placeholders for uniform directions).
pub struct BundleDirections {
    density: DirectionDensity,
    table: EquirectTable,
}

impl BundleDirections {
    /// `density` Environment on a scene without a map is uniform; `offset` is Lo.
    pub fn new(
        ctx: &Context,
        scene: &GpuScene,
        density: DirectionDensity,
        offset: f32,
    ) -> GpuResult<Self> {
        let table =
            EquirectTable::new(ctx, scene, offset, density == DirectionDensity::Environment)?;
        let density = if table.is_built() {
            density
        } else {
            DirectionDensity::Uniform
        };
        Ok(BundleDirections { density, table })
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
        self.table.bindings()
    }

    /// Rebuilds the table from the map (nothing for uniform directions).
    pub fn record<'a>(&'a self, cmd: &mut Commands<'a>, scene: &'a GpuScene) -> GpuResult<()> {
        self.table.record(cmd, scene)
    }
}
