//! Rendering methods (docs/DESIGN.md "Methods"): each method is a set of passes over the shared
//! G-buffer, BVH, samplers and accumulation buffer. `reference` is the ground truth.

pub mod accumulation;
pub mod across_frames;
pub mod bir;
pub mod bsdf_draws;
pub mod bundles;
pub mod compensation;
pub mod device_fit;
pub mod direct;
pub mod direct_alpha;
pub mod driver;
pub mod envmap;
pub mod equirect_table;
pub mod gbuffer;
pub mod interface;
pub mod ir;
pub mod lightfield;
pub mod lights;
pub mod method;
pub mod paths;
pub mod progressive;
pub mod rebuild;
pub mod reference;
pub mod registry;
pub mod renderers;
pub mod restir;
pub mod scene_kernel;
pub mod settings;

pub use across_frames::{AcrossFrames, AnimationFrame, Carried, Change, Changes, PreviousFrame};
pub use driver::{Extras, MethodFrames, Shared};
pub use interface::{Lights, RenderMethod, Renderer, SharedPasses, Support};
pub use method::Method;
pub use registry::Registry;
pub use renderers::{Renderers, RunError};
pub use settings::ParamError;

use crate::gpu::PassTotals;
use crate::image::Image;

/// What every method returns.
pub struct RenderOutput {
    pub image: Image,
    pub passes: PassTotals,
    /// Wall clock of the whole render on the host, submissions and waits included.
    pub wall_ms: f64,
    /// Per-pixel estimates that were NaN or Inf and were dropped (0 in a correct run).
    pub nonfinite_estimates: u32,
    /// Method-specific figures for records and reports (bir: the fraction of kept VPLs from
    /// each side, rays per kept VPL), by name.
    pub stats: Vec<(String, f64)>,
    /// Per-pixel maps written beside the image as `<out>.<name>.exr` and `.png` (env alpha:
    /// "alpha", the light and BRDF shares), by name.
    pub maps: Vec<(String, Image)>,
}
