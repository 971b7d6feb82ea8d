//! The method interface (docs/DESIGN.md "The method interface"): what a method implements
//! once, `RenderMethod`, and `Renderer`, which renders one method through the driver.
//!
//! A method is a type that holds its kernels. Its constants say what it is (name, summary,
//! settings table, the count a time budget calibrates, the lights it renders); its functions
//! say how its frames run (the shared passes it wants, its setup per render, its device-size
//! checks). Everything else (the G-buffer, the direct light, accumulation, progressive
//! submissions, progress, timings, the output, the refusals) is the driver's and the
//! registry's, written once.
//!
//! Why a trait with associated constants and a settings type, and not a trait object with
//! string-keyed settings: a method's own code reads its settings as its own struct (enums,
//! not strings), the compiler checks that every method states every item (no `_ =>` arm to
//! forget), and the registry erases the type in one place (registry.rs) for the code that
//! picks a method by name.

use std::fmt;
use std::time::Instant;

use crate::gpu::{Context, GpuError, GpuResult};
use crate::scene::gpu::GpuScene;
use crate::scene::Scene;

use super::across_frames::{AcrossFrames, AnimationFrame};
use super::direct::{DirectLightOptions, GBufferAndDirectLight};
use super::driver::{self, MethodFrames, Plan};
use super::gbuffer::PixelSampling;
use super::settings::{Kind, Setting, Value};
use super::{lights, RenderOutput, RunError};

pub use super::lights::{Lights, Support};

/// A rendering method. Implement it once, in the method's module, and list the type in a
/// `Registry` (`Registry::builtin` for irad's own, `Registry::with` for one of yours).
pub trait RenderMethod: Sized + 'static {
    /// The method's settings, built from `SETTINGS` (its `Default` is every default).
    type Settings: Clone + fmt::Debug + PartialEq + Default + Send + Sync + 'static;

    /// The name `--method` and suite files use.
    const NAME: &'static str;
    /// What it is, in one line, for `irad methods`.
    const SUMMARY: &'static str;
    /// Its settings table (src/methods/settings.rs). It holds a Count row `seed` and the
    /// Count row `COUNT`; `Registry::with` checks both.
    const SETTINGS: &'static [Setting<Self::Settings>];
    /// The Count row a time budget calibrates and the driver runs as frames: "spp" for the
    /// reference (one path per pixel a frame), "frames" for the others.
    const COUNT: &'static str;
    /// The lights it renders, declines or needs: data, turned into refusals in one place
    /// (lights.rs).
    const LIGHTS: Lights;
    /// What it keeps from one animation frame to the next and what invalidates it
    /// (across_frames.rs): `AcrossFrames::NOTHING` where each frame starts from scratch.
    const ACROSS_FRAMES: AcrossFrames;

    /// What a render with `settings` keeps from one animation frame to the next:
    /// `ACROSS_FRAMES`, or nothing where a setting turns the reuse off (ir's `reuse = 1`), so
    /// that the driver hands such a render no previous frame.
    fn across_frames(settings: &Self::Settings) -> AcrossFrames {
        let _ = settings;
        Self::ACROSS_FRAMES
    }

    /// Builds the method's kernels (once per `Renderers`, however many renders follow).
    fn new(ctx: &Context) -> GpuResult<Self>;

    /// The shared passes each frame records before the method's own: how pixels are sampled
    /// and the direct light, if any.
    fn shared_passes(settings: &Self::Settings) -> SharedPasses;

    /// Sets up one render (buffers, tables) and returns its frames for the driver. `animation`
    /// says which animation frame `scene` is and hands the previous frame's scene with what
    /// changed since, for a render that carries state across frames (`across_frames`).
    fn set_up<'a>(
        &'a self,
        ctx: &Context,
        scene: &Scene,
        gpu_scene: &GpuScene,
        settings: &'a Self::Settings,
        animation: &AnimationFrame<'_>,
    ) -> GpuResult<Box<dyn MethodFrames + 'a>>;

    /// Work in units that scale the method's cost at a fixed resolution, for time estimates;
    /// by default its count.
    fn work(settings: &Self::Settings) -> f64 {
        count::<Self>(settings) as f64
    }

    /// Refuses, in the user's words (the setting or scene field and the largest value that
    /// fits), sizes whose buffers would pass the device's maxStorageBufferRange `limit`
    /// (device_fit.rs has the helpers). By default nothing is refused beyond the G-buffer's
    /// size, which `device_fit::check_scene` checks for every method.
    fn fits(settings: &Self::Settings, scene: &Scene, limit: u64) -> Result<(), String> {
        let _ = (settings, scene, limit);
        Ok(())
    }

    /// What a record states besides the settings table's values (lightfield: that a
    /// sampling-only image is black); none by default.
    fn record_notes(settings: &Self::Settings) -> Vec<(&'static str, serde_json::Value)> {
        let _ = settings;
        Vec::new()
    }
}

/// The passes the driver records each frame before a method's own.
#[derive(Clone, Copy, Debug)]
pub struct SharedPasses {
    /// How the G-buffer samples each pixel.
    pub pixels: PixelSampling,
    /// The direct-light pass after the G-buffer, or none.
    pub direct: Option<DirectLightOptions>,
}

/// `row`'s Count value in `s`.
fn count_row<M: RenderMethod>(s: &M::Settings, row: &str) -> u32 {
    match M::SETTINGS
        .iter()
        .find(|r| r.key == row)
        .and_then(|r| (r.get)(s))
    {
        Some(Value::Count(n)) => n,
        _ => unreachable!("Registry::with checks {}'s Count row {row}", M::NAME),
    }
}

/// `s` with `row`'s Count value set to `n`.
fn set_count_row<M: RenderMethod>(s: &mut M::Settings, row: &str, n: u32) {
    let r = M::SETTINGS.iter().find(|r| r.key == row);
    (r.expect("Registry::with checks the row").set)(s, Value::Count(n));
}

/// The count a time budget calibrates (`M::COUNT`'s value).
pub fn count<M: RenderMethod>(s: &M::Settings) -> u32 {
    count_row::<M>(s, M::COUNT)
}

pub fn set_count<M: RenderMethod>(s: &mut M::Settings, n: u32) {
    set_count_row::<M>(s, M::COUNT, n)
}

pub fn seed<M: RenderMethod>(s: &M::Settings) -> u32 {
    count_row::<M>(s, "seed")
}

pub fn set_seed<M: RenderMethod>(s: &mut M::Settings, seed: u32) {
    set_count_row::<M>(s, "seed", seed)
}

/// Why `M`'s table cannot serve the interface, or None: the rows `seed` and `M::COUNT`
/// must be Count rows.
pub fn table_problem<M: RenderMethod>() -> Option<String> {
    for key in ["seed", M::COUNT] {
        match M::SETTINGS.iter().find(|r| r.key == key) {
            Some(r) if matches!(r.kind, Kind::Count { .. }) => {}
            Some(_) => return Some(format!("{}: setting {key} is not a Count", M::NAME)),
            None => return Some(format!("{}: no setting {key} in its table", M::NAME)),
        }
    }
    None
}

/// Why `M` declines `scene`'s lights, in one line, or None.
pub fn declines<M: RenderMethod>(scene: &Scene) -> Option<String> {
    lights::declines(M::NAME, &M::LIGHTS, scene)
}

/// Panics naming the problem where `M`'s table cannot serve the interface (a method's code
/// is wrong, whatever the input).
pub fn assert_table<M: RenderMethod>() {
    if let Some(problem) = table_problem::<M>() {
        panic!("method {problem}");
    }
}

/// Renders `scene` with `method`'s kernels and the shared `passes`: the refusals (lights,
/// device sizes), then the driver.
#[allow(clippy::too_many_arguments)]
pub(crate) fn render<M: RenderMethod>(
    passes: &GBufferAndDirectLight,
    method: &M,
    ctx: &Context,
    scene: &Scene,
    gpu_scene: &GpuScene,
    settings: &M::Settings,
    animation: &AnimationFrame<'_>,
    progress: impl FnMut(u32, u32),
) -> Result<RenderOutput, RunError> {
    if let Some(why) = declines::<M>(scene) {
        return Err(RunError::Declined(why));
    }
    // The loaded scene holds the file's own values, which frame 0's tracks may override (a
    // light on a track starting switched off): a render shows one frame, built by at_frame.
    if let Some(animation) = &scene.animation {
        return Err(RunError::Animated(format!(
            "{} is animated ({} frames): render one frame of it (Scene::at_frame, `irad render \
             --frame N`) or all of them (irad::sequence, `irad render --sequence`)",
            scene
                .source
                .as_ref()
                .map_or(scene.name.clone(), |p| p.display().to_string()),
            animation.frames
        )));
    }
    let limit = ctx.info().max_storage_buffer_range;
    M::fits(settings, scene, limit).map_err(|e| RunError::Gpu(GpuError::DoesNotFit(e)))?;
    // A cut traversal left over from an earlier render (one that failed before its check)
    // is not this render's; progressive::run checks it after every submission.
    gpu_scene.bvh.clear_loop_cuts()?;
    let start = Instant::now();
    let shared = M::shared_passes(settings);
    let plan = Plan {
        frames: count::<M>(settings).max(1),
        seed: seed::<M>(settings),
        pixels: shared.pixels,
        direct: shared.direct,
        start,
    };
    let setup = || method.set_up(ctx, scene, gpu_scene, settings, animation);
    Ok(driver::render(
        ctx, passes, gpu_scene, plan, setup, progress,
    )?)
}

/// One method's kernels with the shared passes': renders `M` without a registry (tests,
/// benchmarks that time one method).
pub struct Renderer<M> {
    passes: GBufferAndDirectLight,
    method: M,
}

impl<M: RenderMethod> Renderer<M> {
    /// Panics where `M`'s table lacks the Count rows `seed` and `M::COUNT` (as
    /// `Registry::with`).
    pub fn new(ctx: &Context) -> GpuResult<Renderer<M>> {
        assert_table::<M>();
        Ok(Renderer {
            passes: GBufferAndDirectLight::new(ctx)?,
            method: M::new(ctx)?,
        })
    }

    /// The method's own kernels.
    pub fn method(&self) -> &M {
        &self.method
    }

    /// Renders `scene` (uploaded as `gpu_scene`) with `settings`, calling
    /// `progress(done, total)` as frames complete; refused where `M` declines the scene's
    /// lights or the sizes do not fit the device.
    pub fn render(
        &self,
        ctx: &Context,
        scene: &Scene,
        gpu_scene: &GpuScene,
        settings: &M::Settings,
        progress: impl FnMut(u32, u32),
    ) -> Result<RenderOutput, RunError> {
        self.render_frame(
            ctx,
            scene,
            gpu_scene,
            settings,
            &AnimationFrame::STILL,
            progress,
        )
    }

    /// `render` of one animation frame (`scene` the frame's, `Scene::at_frame`), handing the
    /// method `animation`.
    pub fn render_frame(
        &self,
        ctx: &Context,
        scene: &Scene,
        gpu_scene: &GpuScene,
        settings: &M::Settings,
        animation: &AnimationFrame<'_>,
        progress: impl FnMut(u32, u32),
    ) -> Result<RenderOutput, RunError> {
        render(
            &self.passes,
            &self.method,
            ctx,
            scene,
            gpu_scene,
            settings,
            animation,
            progress,
        )
    }
}
