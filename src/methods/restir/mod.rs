//! ReSTIR DI (Bitterli et al. 2020; NVIDIA's RTXDI): the direct light of every emitter irad has
//! (emissive triangles, point and spot lights, the environment map) by reservoir resampling.
//! Per pixel and frame: M light candidates (through the light BVH or the power table; the
//! environment by its share of the table) and B BSDF candidates combined by multiple importance
//! resampling, the target being the unshadowed contribution; a shadow ray for the chosen sample
//! (pass "restir candidates"); the previous frame's reservoir of the same pixel, its M capped
//! (pass "restir temporal"); k neighbours within R pixels, rejected by normal and depth (pass
//! "restir spatial"); the final sample shaded (pass "restir shade"). Unbiased combination by MIS
//! (the balance heuristic over p^ V, pairwise in space) by default; 1 / Z with visibility
//! (Alg. 6) and the biased 1 / sum M (Alg. 4-5) as settings. The emission the camera sees is
//! the driver's direct-light pass at depth 0. Direct light only: it is scored against the path
//! tracer at `max_depth` 1.

pub mod kernels;

use crate::gpu::{Commands, Context, GpuResult};
use crate::scene::gpu::GpuScene;
use crate::scene::Scene;

use super::across_frames::{AcrossFrames, AnimationFrame};
use super::direct::{DirectLightOptions, DirectLightPaths};
use super::driver::{MethodFrames, Shared};
use super::gbuffer::PixelSampling;
use super::interface::{Lights, RenderMethod, SharedPasses, Support};
use super::lights::NO_LUMINAIRES;
use super::paths::LightSampler;
use super::settings::{common_settings, field_setting, named_choices, Kind, Need, Setting, Value};

use kernels::{
    FrameInputs, GenerateCandidates, ReservoirBuffers, ReuseSpatial, ReuseTemporal, ShadeRestir,
};

/// How reservoirs are combined in reuse.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Combination {
    /// The balance heuristic over the reservoirs' p^ V, pairwise in space (Bitterli's thesis
    /// Section 9.1; Lin et al. 2022, GRIS), with confidence weights: unbiased, its weights
    /// bounded by the targets' ratio.
    Mis,
    /// 1 / Z, Z the confidence of the reservoirs whose surface could have produced the sample,
    /// visibility included (Bitterli et al. Alg. 6): unbiased, its weights unbounded.
    OneOverZ,
    /// 1 / (sum of M) (Alg. 4-5): biased where neighbours' surfaces or visibility differ.
    Biased,
}

named_choices!(Combination {
    Mis => "mis",
    OneOverZ => "one-over-z",
    Biased => "biased",
});

impl Combination {
    /// The kernels' COMBINATION_* (glsl/include/restir.glsl).
    pub(crate) fn gpu_code(self) -> u32 {
        match self {
            Combination::Biased => 0,
            Combination::OneOverZ => 1,
            Combination::Mis => 2,
        }
    }

    pub fn is_unbiased(self) -> bool {
        self != Combination::Biased
    }
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RestirSettings {
    pub frames: u32,
    pub seed: u32,
    /// M: light candidates per pixel and frame.
    pub candidates: u32,
    /// B: BSDF candidates per pixel and frame.
    pub bsdf_candidates: u32,
    pub light_sampler: LightSampler,
    /// Reuse of the previous frame's reservoir.
    pub temporal: bool,
    /// The previous reservoir's M at most this times the frame's candidates.
    pub temporal_cap: u32,
    /// k, neighbours of spatial reuse (0: none).
    pub neighbours: u32,
    /// R, pixels.
    pub radius: u32,
    pub combination: Combination,
    pub pixels: PixelSampling,
}

impl Default for RestirSettings {
    fn default() -> Self {
        RestirSettings {
            frames: 16,
            seed: 0,
            candidates: 32,
            bsdf_candidates: 1,
            light_sampler: LightSampler::Bvh,
            temporal: true,
            temporal_cap: 20,
            neighbours: 5,
            radius: 30,
            combination: Combination::Mis,
            pixels: PixelSampling::Jittered,
        }
    }
}

/// Most light candidates: each is a light-BVH descent of at most 64 levels in one invocation,
/// and lavapipe stops an invocation's loops after 65535 iterations in all (docs/DESIGN.md "The
/// loop budget"): 512 x (64 + a texel or table search of up to 24) leaves about 20000
/// iterations to the rays.
pub const MAX_CANDIDATES: u32 = 512;

pub const SETTINGS: &[Setting<RestirSettings>] = &[
    common_settings!(
        frames,
        "Frames, each one sample per pixel after reuse; the temporal reuse carries reservoirs \
         from one frame to the next within a render."
    ),
    common_settings!(seed),
    field_setting!(
        "candidates",
        candidates,
        Kind::Count {
            min: 1,
            max: MAX_CANDIDATES
        },
        Count,
        "M: light candidates per pixel and frame (light_sampler's choice, the environment by its \
         power share), resampled by the unshadowed contribution.",
    ),
    field_setting!(
        "bsdf_candidates",
        bsdf_candidates,
        Kind::Count { min: 0, max: 16 },
        Count,
        "B: BSDF-sampled candidates per pixel and frame (an emissive hit or the environment), \
         combined with the light candidates by the balance heuristic.",
    ),
    common_settings!(
        light_sampler,
        "How light candidates are drawn: bvh (the light BVH, by each light's bound on what it \
         sends to the point) or power (the light table)."
    ),
    field_setting!(
        "temporal",
        temporal,
        Kind::Switch,
        Switch,
        "Reuse each pixel's final reservoir of the previous frame.",
    ),
    field_setting!(
        "temporal_cap",
        temporal_cap,
        Kind::Count { min: 1, max: 1000 },
        Count,
        "The previous reservoir's M at most this times the frame's candidates (the paper's 20).",
        needs: &[Need::OneOf("temporal", &["true"])],
    ),
    field_setting!(
        "neighbours",
        neighbours,
        Kind::Count { min: 0, max: 16 },
        Count,
        "k: neighbours of spatial reuse within radius pixels, rejected where normals differ by \
         more than about 25 degrees or camera distances by more than 10% (0: no spatial reuse).",
    ),
    field_setting!(
        "radius",
        radius,
        Kind::Count { min: 1, max: 256 },
        Count,
        "R: spatial reuse's radius in pixels.",
        needs: &[Need::Not("neighbours", "0")],
    ),
    Setting::<RestirSettings>::new(
        "combination",
        Kind::Choice(Combination::NAMES),
        "mis: the balance heuristic over each reservoir's target times visibility, pairwise \
         in space (two shadow rays per neighbour); unbiased, its weights bounded by how the \
         targets differ between surfaces. one-over-z: 1 / Z over the reservoirs whose surface \
         could have produced the sample, visibility included (a shadow ray per reservoir \
         reused); unbiased, but its weights ignore how the target differs between surfaces, \
         so on glossy lobes and grazing emitters reuse brings spikes that an image averaged \
         over frames keeps (README \"restir and the light BVH\"). biased: 1 / (sum of M), \
         darker where the pixel receives light its neighbours cannot (beside shadow edges, \
         across normal changes; the README gives its bias).",
        |s| Some(Value::Name(s.combination.name())),
        |s, v| {
            s.combination = Combination::from_name(v.name()).expect("a checked name");
        },
    )
    // It combines reservoirs in reuse only.
    .needs(&[Need::Any(&[
        Need::OneOf("temporal", &["true"]),
        Need::Not("neighbours", "0"),
    ])]),
    common_settings!(pixel_centres),
];

pub struct Restir {
    candidates: GenerateCandidates,
    temporal: ReuseTemporal,
    spatial: ReuseSpatial,
    shade: ShadeRestir,
}

impl RenderMethod for Restir {
    type Settings = RestirSettings;
    const NAME: &'static str = "restir";
    const SUMMARY: &'static str =
        "ReSTIR DI (Bitterli et al. 2020): direct light by spatiotemporal reservoir resampling.";
    const SETTINGS: &'static [Setting<RestirSettings>] = SETTINGS;
    const COUNT: &'static str = "frames";
    const LIGHTS: Lights = Lights {
        environment: Support::Renders,
        area: Support::Renders,
        point: Support::Renders,
        luminaires: Support::Declines(NO_LUMINAIRES),
    };
    const ACROSS_FRAMES: AcrossFrames = AcrossFrames::NOTHING;

    fn new(ctx: &Context) -> GpuResult<Self> {
        Ok(Restir {
            candidates: GenerateCandidates::new(ctx)?,
            temporal: ReuseTemporal::new(ctx)?,
            spatial: ReuseSpatial::new(ctx)?,
            shade: ShadeRestir::new(ctx)?,
        })
    }

    /// The emission the camera sees (depth 0); the reflected direct light is the method's.
    fn shared_passes(settings: &RestirSettings) -> SharedPasses {
        SharedPasses {
            pixels: settings.pixels,
            direct: Some(DirectLightOptions {
                light: DirectLightPaths::EmissionOnly,
                reflected_environment: true,
                spp: 1,
            }),
        }
    }

    fn work(s: &RestirSettings) -> f64 {
        s.frames as f64 * (s.candidates + s.bsdf_candidates + s.neighbours + 2) as f64
    }

    fn set_up<'a>(
        &'a self,
        ctx: &Context,
        _scene: &Scene,
        gpu_scene: &GpuScene,
        settings: &'a RestirSettings,
        _animation: &AnimationFrame<'_>,
    ) -> GpuResult<Box<dyn MethodFrames + 'a>> {
        Ok(Box::new(RestirFrames {
            restir: self,
            settings,
            reservoirs: ReservoirBuffers::new(ctx, gpu_scene.pixel_count())?,
        }))
    }
}

struct RestirFrames<'a> {
    restir: &'a Restir,
    settings: &'a RestirSettings,
    reservoirs: ReservoirBuffers,
}

impl MethodFrames for RestirFrames<'_> {
    fn record<'a>(
        &'a self,
        shared: &Shared<'a>,
        cmd: &mut Commands<'a>,
        frame: u32,
    ) -> GpuResult<()> {
        let (restir, s) = (self.restir, self.settings);
        let inputs = FrameInputs {
            scene: shared.scene,
            gbuffer: shared.gbuffer,
            reservoirs: &self.reservoirs,
            frame,
            seed: s.seed,
        };
        cmd.pass("restir candidates", |cmd| {
            restir.candidates.record(
                cmd,
                &inputs,
                s.candidates,
                s.bsdf_candidates,
                s.light_sampler == LightSampler::Bvh,
                shared.accumulation,
            )
        })?;
        if s.temporal {
            cmd.pass("restir temporal", |cmd| {
                restir.temporal.record(
                    cmd,
                    &inputs,
                    s.temporal_cap,
                    s.combination,
                    shared.accumulation,
                )
            })?;
        }
        // With no neighbours it still stores the final reservoirs and surfaces.
        cmd.pass("restir spatial", |cmd| {
            restir.spatial.record(
                cmd,
                &inputs,
                s.neighbours,
                s.radius,
                s.combination,
                shared.accumulation,
            )
        })?;
        cmd.pass("restir shade", |cmd| {
            restir.shade.record(cmd, &inputs, shared.accumulation)
        })
    }
}
