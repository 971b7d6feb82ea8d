//! irad: a research renderer for many-light and light-source importance sampling, run as
//! Vulkan compute kernels through raw `ash`. See DESIGN.md (shared/) for the map.

pub mod bench;
pub mod bvh;
pub mod export;
pub mod gpu;
pub mod image;
pub mod methods;
pub mod render;
pub mod sampling;
pub mod scene;
pub mod selfcheck;
pub mod shaders;
pub mod trace;
