//! irad: a research renderer for many-light and light-source importance sampling, run as
//! Vulkan compute kernels through raw `ash`. docs/DESIGN.md is the map.
//!
//! A render in memory: a Vulkan context, a scene (from a TOML file with `scene::load`, or the
//! embedded Cornell box), the scene uploaded, a method with its settings (built as a struct,
//! or by name from the keys `irad methods NAME` lists, as a suite file gives them), and the
//! image it returns, with its per-pass GPU times. A method of your own is a `RenderMethod`
//! added to a `Registry` (docs/adding-a-method.md, examples/custom_method.rs):
//!
//! ```
//! use irad::methods::reference::Reference;
//! use irad::{Context, ContextOptions, GpuScene, Method, ReferenceSettings, Renderers};
//!
//! # fn main() -> anyhow::Result<()> {
//! // The first GPU, else lavapipe; from_env reads IRAD_DEVICE, IRAD_VALIDATE and
//! // IRAD_FORCE_STAGING (ContextOptions::default() ignores the environment).
//! let ctx = Context::new(&ContextOptions::from_env()?)?;
//! let mut scene = irad::scene::default_scene();
//! (scene.camera.width, scene.camera.height) = (32, 24);
//! let gpu_scene = GpuScene::upload(&ctx, &scene)?;
//! let renderers = Renderers::default(); // each method's kernels, built on first use
//!
//! let reference = Method::new::<Reference>(ReferenceSettings { spp: 4, ..Default::default() });
//! let ir = Method::from_params("ir", &toml::from_str("vpls = 32\nframes = 2")?)?;
//! for method in [reference, ir] {
//!     let out = renderers.run(&ctx, &method, &scene, &gpu_scene, |_done, _total| {})?;
//!     let (w, h) = (out.image.width, out.image.height);
//!     let mean = out.image.pixels.iter().map(|p| p[1]).sum::<f32>() / (w * h) as f32;
//!     assert!(mean > 0.0 && mean.is_finite());
//!     println!("{}: {w}x{h}, mean green {mean:.3}, {}", method.name(), out.passes);
//! }
//! # Ok(())
//! # }
//! ```
//!
//! `render::render` does the same from a `RenderJob` and writes the EXR, PNG and JSON record
//! as `irad render` does. Warnings (a scene's dropped triangles, a render's suspicious
//! figures) go through the `log` facade as well as into `Scene::warnings` and the record;
//! the `irad` binary prints them as `warning: ...` on stderr.

pub mod bench;
pub mod bvh;
pub mod export;
pub mod gpu;
pub mod html;
pub mod image;
pub mod lock;
pub mod methods;
pub mod render;
pub mod sampling;
pub mod scene;
pub mod sequence;
pub mod trace;

pub use gpu::{Context, ContextOptions, DeviceSelector, GpuError, Validation};
pub use image::Image;
pub use methods::bir::BirSettings;
pub use methods::bundles::BundlesSettings;
pub use methods::envmap::EnvSettings;
pub use methods::ir::IrSettings;
pub use methods::lightfield::LightfieldSettings;
pub use methods::reference::ReferenceSettings;
pub use methods::{
    Method, ParamError, Registry, RenderMethod, RenderOutput, Renderer, Renderers, RunError,
};
pub use render::{render, RenderJob};
pub use scene::gpu::GpuScene;
pub use scene::{Scene, SceneError};
