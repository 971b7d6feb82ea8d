//! Rendering methods (DESIGN.md): each method is a set of passes over the shared G-buffer,
//! BVH, samplers and accumulation buffer. `reference` is the ground truth.

pub mod accumulation;
pub mod gbuffer;
pub mod ir;
pub mod paths;
pub mod progressive;
pub mod reference;
