//! The reference path tracer, ground truth for every accuracy figure: per frame, the G-buffer
//! pass then glsl/shared/trace_reference_paths.comp (one path per pixel: next-event estimation plus
//! BSDF sampling combined by the power heuristic, Russian roulette), accumulated over `spp`
//! frames. Unbiased up to `max_depth` scattering events (a safety cap; Russian roulette ends
//! paths long before it unless the scene reflects almost everything).

use crate::gpu::{Buffer, Commands, Context, GpuResult};
use crate::scene::gpu::GpuScene;
use crate::scene::Scene;

use super::across_frames::{AcrossFrames, AnimationFrame};
use super::direct_alpha::ShadeDirectAlpha;
use super::driver::{Extras, MethodFrames, Shared};
use super::envmap;
use super::gbuffer::PixelSampling;
use super::interface::{Lights, RenderMethod, SharedPasses, Support};
use super::paths::{LightSampler, PathStarts};
use super::settings::{common_settings, field_setting, with_needs, Kind, Need, Setting, Value};

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ReferenceSettings {
    /// Samples (paths) per pixel, one per frame.
    pub spp: u32,
    pub seed: u32,
    /// Most scattering events per path.
    pub max_depth: u32,
    /// First bounce at which Russian roulette may end a path.
    pub roulette_depth: u32,
    /// With `max_depth` 1 only: Lu 14 Chapter 5's per-pixel split of the direct light between
    /// light and BSDF sampling, estimated over the first M frames (glsl/shared/shade_direct_alpha.comp)
    /// instead of the power heuristic's one sample of each.
    pub alpha_frames: Option<u32>,
    /// How next-event estimation chooses its light: by power or through the light BVH.
    pub light_sampler: LightSampler,
    pub pixels: PixelSampling,
}

impl Default for ReferenceSettings {
    fn default() -> Self {
        ReferenceSettings {
            spp: 64,
            seed: 0,
            max_depth: 1024,
            roulette_depth: 3,
            alpha_frames: None,
            // The light BVH, as restir's: at equal time it is 2.2-2.7x the power table on the
            // many-light halls and about 1.17x behind it on the Cornell box (two lights in one
            // box: the descent is all it adds; docs/methods/light-bvh.md), so it loses little
            // where it does not help and wins where the light count makes sampling matter.
            light_sampler: LightSampler::Bvh,
            pixels: PixelSampling::Jittered,
        }
    }
}

/// The reference's settings (`irad methods reference`).
pub const SETTINGS: &[Setting<ReferenceSettings>] = &[
    field_setting!(
        "spp",
        spp,
        Kind::Count {
            min: 1,
            max: u32::MAX
        },
        Count,
        "Samples per pixel: one path per pixel per frame.",
    ),
    common_settings!(seed),
    field_setting!(
        "max_depth",
        max_depth,
        // A path's bounces run in one kernel invocation, whose loops lavapipe stops silently
        // after 65535 iterations in all (docs/DESIGN.md "The loop budget"): two traversals a
        // bounce, so 1024 bounces (the default) is as far as a path in a closed, white scene
        // may go. With light_sampler bvh a bounce adds a descent and, at an emissive hit, a pmf
        // walk (tens of levels each on real scenes); the budget spent there cuts the path's
        // next traversal, which LoopCuts reports (the render is refused), unless nothing of
        // the path is left to trace.
        Kind::Count { min: 1, max: 1024 },
        Count,
        "Most scattering events per path (a safety cap: Russian roulette ends paths first).",
    ),
    field_setting!(
        "roulette_depth",
        roulette_depth,
        // Without roulette every path of a closed scene runs to max_depth (see max_depth).
        Kind::Count { min: 0, max: 64 },
        Count,
        "First bounce at which Russian roulette may end a path.",
        // alpha_frames shades the direct light without paths.
        needs: &[Need::Unset("alpha_frames")],
    ),
    Setting::<ReferenceSettings>::new(
        "alpha_frames",
        Kind::Count {
            min: 0,
            max: u32::MAX,
        },
        "With max_depth 1: split the direct light between light and BSDF sampling per pixel \
         by Lu 14 ch. 5's alpha, estimated over the first M frames (one sample of each, \
         balance heuristic); later frames take 2 alpha BSDF and 2 (1 - alpha) light samples. \
         Writes OUT.alpha.{exr,png} (red: light, green: BSDF).",
        |s| s.alpha_frames.map(Value::Count),
        |s, v| s.alpha_frames = Some(v.count()),
    )
    .unset("off (the power heuristic's one light and one BSDF sample)")
    // It splits the direct light only.
    .needs(&[Need::OneOf("max_depth", &["1"])]),
    // alpha's direct light draws its own light samples by power.
    with_needs(
        &[Need::Unset("alpha_frames")],
        common_settings!(
            light_sampler,
            "How next-event estimation chooses its light: power (in proportion to each light's \
             power, one table for every point) or bvh (pbrt-v4's light BVH: by each light's bound \
             on what it sends to the shading point; the environment map keeps its power share). \
             bvh is the default, as restir's: 2.2-2.7x the power table at equal time on the \
             many-light halls, about 1.17x behind it where a scene has a light or two."
        ),
    ),
    common_settings!(pixel_centres),
];

pub struct Reference {
    alpha: ShadeDirectAlpha,
}

impl RenderMethod for Reference {
    type Settings = ReferenceSettings;
    const NAME: &'static str = "reference";
    const SUMMARY: &'static str =
        "The unbiased path tracer every accuracy figure is measured against.";
    const SETTINGS: &'static [Setting<ReferenceSettings>] = SETTINGS;
    /// One path per pixel a frame.
    const COUNT: &'static str = "spp";
    const LIGHTS: Lights = Lights {
        environment: Support::Renders,
        area: Support::Renders,
        point: Support::Renders,
        luminaires: Support::Declines("the path tracer does not model them"),
    };
    const ACROSS_FRAMES: AcrossFrames = AcrossFrames::NOTHING;

    fn new(ctx: &Context) -> GpuResult<Reference> {
        Ok(Reference {
            alpha: ShadeDirectAlpha::new(ctx)?,
        })
    }

    /// The G-buffer alone: the paths (or alpha's direct light) are the reference's own.
    fn shared_passes(settings: &ReferenceSettings) -> SharedPasses {
        SharedPasses {
            pixels: settings.pixels,
            direct: None,
        }
    }

    fn set_up<'a>(
        &'a self,
        ctx: &Context,
        _scene: &Scene,
        gpu_scene: &GpuScene,
        settings: &'a ReferenceSettings,
        _animation: &AnimationFrame<'_>,
    ) -> GpuResult<Box<dyn MethodFrames + 'a>> {
        Ok(Box::new(ReferenceFrames {
            reference: self,
            settings,
            alpha_frames: settings.alpha_frames.filter(|_| settings.max_depth == 1),
            state: ShadeDirectAlpha::state(ctx, gpu_scene)?,
        }))
    }
}

/// One reference render: its paths, or alpha's direct light and state.
struct ReferenceFrames<'a> {
    reference: &'a Reference,
    settings: &'a ReferenceSettings,
    alpha_frames: Option<u32>,
    state: Buffer<[f32; 4]>,
}

impl MethodFrames for ReferenceFrames<'_> {
    fn record<'a>(
        &'a self,
        shared: &Shared<'a>,
        cmd: &mut Commands<'a>,
        frame: u32,
    ) -> GpuResult<()> {
        let (reference, settings) = (self.reference, self.settings);
        if let Some(m) = self.alpha_frames {
            return cmd.pass("direct light alpha", |cmd| {
                reference.alpha.record(
                    cmd,
                    shared.scene,
                    shared.gbuffer,
                    shared.accumulation,
                    &self.state,
                    frame,
                    settings.seed,
                    m,
                )
            });
        }
        cmd.pass("reference paths", |cmd| {
            shared.passes.paths().record(
                cmd,
                shared.scene,
                shared.gbuffer,
                shared.accumulation,
                frame,
                settings.seed,
                settings.max_depth,
                settings.roulette_depth,
                true,
                PathStarts::GBuffer,
                settings.light_sampler,
            )
        })
    }

    fn finish(&self, shared: &Shared<'_>) -> GpuResult<Extras> {
        let mut extras = Extras::default();
        if self.alpha_frames.is_some() {
            // Per pixel: alpha's mean over the frames from M on that saw a surface there.
            let sums: Vec<[f32; 2]> = self.state.read()?.iter().map(|s| [s[3], s[2]]).collect();
            extras
                .stats
                .push(("mean_alpha".into(), envmap::mean_alpha(&sums)));
            extras.maps.push((
                "alpha".into(),
                envmap::alpha_map(&sums, shared.scene.width, shared.scene.height),
            ));
        }
        Ok(extras)
    }
}

/// The kernels a reference image depends on: a change to any of them makes cached references
/// stale (the benchmark harness keys its reference cache on `kernel_hash`).
pub const KERNELS: &[&str] = &[
    "write_gbuffer",
    "trace_reference_paths",
    // The reference of a scene with light-field luminaires is lightfield's restricted
    // strategy: its tables (the scans among them) and its two steps.
    "shade_lightfield",
    "estimate_luminaire_areas",
    "weigh_luminaire_columns",
    "transpose_luminaire_columns",
    "reduce_blocks",
    "scan_blocks",
];

/// FNV-1a 64 of the embedded SPIR-V of `KERNELS`, in order.
pub fn kernel_hash() -> u64 {
    let mut h = crate::scene::hash::Fnv1a64::default();
    for name in KERNELS {
        let code = crate::gpu::spirv::embedded(name).unwrap_or_default();
        h.write(name.as_bytes());
        h.write(&(code.len() as u64).to_le_bytes());
        h.write(code);
    }
    h.finish()
}
