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

use std::cell::{Cell, RefCell};
use std::collections::HashMap;

use bytemuck::Zeroable;
use glam::Vec4;

use crate::gpu::{Buffer, Commands, Context, GpuResult};
use crate::scene::gpu::{analytic_lights, camera_constants, gpu_materials, GpuLight, GpuScene};
use crate::scene::Scene;

use super::across_frames::{AcrossFrames, AnimationFrame, Carried, Change};
use super::direct::{DirectLightOptions, DirectLightPaths};
use super::driver::{Extras, MethodFrames, Shared};
use super::gbuffer::PixelSampling;
use super::interface::{Lights, RenderMethod, SharedPasses, Support};
use super::lights::NO_LUMINAIRES;
use super::paths::LightSampler;
use super::settings::{common_settings, field_setting, named_choices, Kind, Need, Setting, Value};

use kernels::{
    CandidateCounts, FrameInputs, GenerateCandidates, History as TemporalHistory, PreviousLighting,
    ReservoirBuffers, ReuseSpatial, ReuseTemporal, ShadeRestir, TemporalOptions,
    TEMPORAL_DEPTH_TOLERANCE, TEMPORAL_NORMAL_COS,
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
    /// T: candidate streams whose picks are shadow-tested, the visible ones resampled again.
    pub candidate_shadow_rays: u32,
    pub light_sampler: LightSampler,
    /// Reuse of the previous frame's reservoir.
    pub temporal: bool,
    /// The previous reservoir's M at most this times the frame's candidates.
    pub temporal_cap: u32,
    /// The cap instead where the lights, emission or map changed since the previous frame.
    pub relit_cap: u32,
    /// Temporal reuse's surface test: the least cosine between shading normals...
    pub temporal_normal: f32,
    /// ...and the most relative difference of distances from the previous camera.
    pub temporal_depth: f32,
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
            candidate_shadow_rays: 1,
            light_sampler: LightSampler::Bvh,
            temporal: true,
            temporal_cap: 20,
            relit_cap: 1,
            temporal_normal: TEMPORAL_NORMAL_COS,
            temporal_depth: TEMPORAL_DEPTH_TOLERANCE,
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

/// Most BSDF candidates (their random-number dimensions in glsl are laid out for this many).
pub const MAX_BSDF_CANDIDATES: u32 = 16;

/// Most candidate streams shadow-tested (glsl's MAX_STREAMS: each stream's pick is held in the
/// invocation's registers until the shadow rays).
pub const MAX_CANDIDATE_SHADOW_RAYS: u32 = 8;

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
        Kind::Count {
            min: 0,
            max: MAX_BSDF_CANDIDATES
        },
        Count,
        "B: BSDF-sampled candidates per pixel and frame (an emissive hit or the environment), \
         combined with the light candidates by the balance heuristic.",
    ),
    field_setting!(
        "candidate_shadow_rays",
        candidate_shadow_rays,
        Kind::Count {
            min: 1,
            max: MAX_CANDIDATE_SHADOW_RAYS
        },
        Count,
        "T: a visibility-aware target for the candidates. They are dealt into T interleaved \
         streams, each resampled by the unshadowed contribution; each stream's pick is \
         shadow-tested and a visible one kept, resampled by the streams' weights (T shadow rays \
         a pixel instead of one; unbiased). Pays where most candidates are hidden: on the \
         many-light hall's walk 2 streams cut relMSE 13% at about the same frame time (one \
         run; scenes/suites/realtime.toml).",
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
        "Reuse the previous frame's final reservoirs: the render's frame before, or for its \
         first frame the previous animation frame's (a sequence), found by projecting each \
         pixel's point through the previous camera and re-weighed under the lights as that \
         frame had them.",
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
        "relit_cap",
        relit_cap,
        Kind::Count { min: 1, max: 1000 },
        Count,
        "temporal_cap for a render whose lights, emission or map changed since the previous \
         animation frame: the history was resampled for light that is no longer there, so the \
         balance heuristic, which weighs it by its M and its target, gives it a share it fills \
         poorly (a light switched off: relMSE 4x that without reuse at 20, 2x at 1; docs/DESIGN.md \
         \"State across frames\").",
        needs: &[Need::OneOf("temporal", &["true"])],
    ),
    field_setting!(
        "temporal_normal",
        temporal_normal,
        Kind::Number,
        Number,
        "Temporal reuse takes the previous frame's surface at this pixel's point seen from the \
         previous camera only where their shading normals' cosine is at least this (RTXDI's \
         0.5; 0 accepts any surface facing the same side)...",
        needs: &[Need::OneOf("temporal", &["true"])],
    ),
    field_setting!(
        "temporal_depth",
        temporal_depth,
        Kind::Number,
        Number,
        "...and their distances from the previous camera differ by at most this fraction of the \
         larger (RTXDI's 0.1); else it searches the pixel's neighbours and reuses nothing where \
         none is alike (a disocclusion).",
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
         over frames keeps (docs/methods/restir.md). biased: 1 / (sum of M), \
         darker where the pixel receives light its neighbours cannot (beside shadow edges, \
         across normal changes; docs/RESULTS.md gives its bias).",
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

/// What restir keeps from one animation frame to the next. No change invalidates it: each is
/// followed (the camera by projecting into the previous frame, the lights, emission and map by
/// evaluating the previous domain under the previous frame's, a light gone by the table's
/// translation), as RTXDI does. It is dropped only where the previous frame's map cannot be
/// read beside this one's (another size, or a map sequence within the frame).
const CARRIED: Carried = Carried {
    state: "each pixel's final reservoir and surface, found again through the previous camera \
            and re-weighed under the previous frame's lights",
    invalidated_by: &[],
};

/// A render's last final reservoirs, kept for the next animation frame's render.
struct History {
    /// The animation frame they were made for, its scene's content hash and its camera: the
    /// previous frame handed to the next render must be this one (another render on the same
    /// kernels in between leaves its own history instead).
    frame: u32,
    content_hash: u64,
    camera: [Vec4; 4],
    size: (u32, u32),
    reservoirs: ReservoirBuffers,
    /// Its light table's entries' identities (`GpuScene::light_keys`).
    light_keys: Vec<u64>,
}

pub struct Restir {
    candidates: GenerateCandidates,
    temporal: ReuseTemporal,
    spatial: ReuseSpatial,
    shade: ShadeRestir,
    /// Left by the last render that completed (across_frames.rs: taken by the next render, and
    /// reused where it renders that frame's successor).
    history: RefCell<Option<History>>,
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
    const ACROSS_FRAMES: AcrossFrames = AcrossFrames {
        carries: &[CARRIED],
    };

    /// Without temporal reuse nothing crosses frames (so a suite gives it no lead-in).
    fn across_frames(settings: &RestirSettings) -> AcrossFrames {
        match settings.temporal {
            true => Self::ACROSS_FRAMES,
            false => AcrossFrames::NOTHING,
        }
    }

    fn new(ctx: &Context) -> GpuResult<Self> {
        Ok(Restir {
            candidates: GenerateCandidates::new(ctx)?,
            temporal: ReuseTemporal::new(ctx)?,
            spatial: ReuseSpatial::new(ctx)?,
            shade: ShadeRestir::new(ctx)?,
            history: RefCell::new(None),
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
        s.frames as f64
            * (s.candidates + s.bsdf_candidates + s.candidate_shadow_rays + s.neighbours + 1) as f64
    }

    fn set_up<'a>(
        &'a self,
        ctx: &Context,
        scene: &Scene,
        gpu_scene: &GpuScene,
        settings: &'a RestirSettings,
        animation: &AnimationFrame<'_>,
    ) -> GpuResult<Box<dyn MethodFrames + 'a>> {
        let size = (gpu_scene.width, gpu_scene.height);
        // Whatever the last render left is taken: reused only by its successor.
        let history = self.history.borrow_mut().take();
        let carried = match (history, animation.previous) {
            (Some(h), Some(p))
                if settings.temporal
                    && animation.keeps(&CARRIED)
                    && h.frame == p.frame
                    && h.content_hash == p.scene.content_hash
                    && h.camera == camera_constants(&p.scene.camera)
                    && h.size == size =>
            {
                previous_lighting(ctx, p.scene, gpu_scene, &h.light_keys)?
                    .map(|lighting| (h.reservoirs, lighting))
            }
            _ => None,
        };
        let (reservoirs, previous) = match carried {
            Some((reservoirs, lighting)) => (reservoirs, Some(lighting)),
            None => (ReservoirBuffers::new(ctx, gpu_scene.pixel_count())?, None),
        };
        Ok(Box::new(RestirFrames {
            restir: self,
            settings,
            reservoirs: Some(reservoirs),
            previous,
            frame: animation.frame,
            content_hash: scene.content_hash,
            camera: gpu_scene.camera,
            lights_changed: animation.previous.is_some_and(|p| {
                p.changed
                    .any_of(&[Change::Lights, Change::Emission, Change::Environment])
            }),
            size,
            light_keys: gpu_scene.light_keys.clone(),
            finished: Cell::new(false),
        }))
    }
}

/// The previous animation frame's camera, emission, lights and map (from its scene) and its
/// light table's entries in this frame's (by `light_keys`, u32::MAX for a light gone); None
/// where its map cannot stand beside this frame's (another size, or a sequence's).
fn previous_lighting(
    ctx: &Context,
    previous: &Scene,
    gpu_scene: &GpuScene,
    previous_keys: &[u64],
) -> GpuResult<Option<PreviousLighting>> {
    let env_texels: Vec<Vec4> = match (&previous.environment, gpu_scene.environment_size) {
        (None, None) => vec![Vec4::ZERO],
        (Some(env), Some([w, h]))
            if env.width == w && env.height == h && previous.environment_sequence.is_empty() =>
        {
            env.texels.iter().map(|t| t.extend(0.0)).collect()
        }
        _ => return Ok(None),
    };
    let entries: HashMap<u64, u32> = gpu_scene
        .light_keys
        .iter()
        .enumerate()
        .map(|(i, &k)| (k, i as u32))
        .collect();
    let mut translation: Vec<u32> = previous_keys
        .iter()
        .map(|k| entries.get(k).copied().unwrap_or(u32::MAX))
        .collect();
    let mut lights = analytic_lights(previous).0;
    // A binding cannot be an empty buffer.
    translation.push(u32::MAX);
    lights.push(GpuLight::zeroed());
    Ok(Some(PreviousLighting {
        camera: camera_constants(&previous.camera),
        materials: Buffer::from_slice(ctx, "PreviousMaterials", &gpu_materials(previous))?,
        lights: Buffer::from_slice(ctx, "PreviousLights", &lights)?,
        env_texels: Buffer::from_slice(ctx, "PreviousEnvTexels", &env_texels)?,
        translation: Buffer::from_slice(ctx, "EntryTranslation", &translation)?,
    }))
}

struct RestirFrames<'a> {
    restir: &'a Restir,
    settings: &'a RestirSettings,
    /// Some until the frames are dropped (then kept as the history of a completed render).
    reservoirs: Option<ReservoirBuffers>,
    /// The previous animation frame's light, where its reservoirs were carried over.
    previous: Option<PreviousLighting>,
    /// The animation frame, its size and its light table's identities, for the history.
    frame: u32,
    content_hash: u64,
    camera: [Vec4; 4],
    size: (u32, u32),
    light_keys: Vec<u64>,
    lights_changed: bool,
    finished: Cell<bool>,
}

impl MethodFrames for RestirFrames<'_> {
    fn record<'a>(
        &'a self,
        shared: &Shared<'a>,
        cmd: &mut Commands<'a>,
        frame: u32,
    ) -> GpuResult<()> {
        let (restir, s) = (self.restir, self.settings);
        let reservoirs = self.reservoirs.as_ref().expect("held until dropped");
        let inputs = FrameInputs {
            scene: shared.scene,
            gbuffer: shared.gbuffer,
            reservoirs,
            frame,
            seed: s.seed,
        };
        cmd.pass("restir candidates", |cmd| {
            restir.candidates.record(
                cmd,
                &inputs,
                CandidateCounts {
                    light: s.candidates,
                    bsdf: s.bsdf_candidates,
                    shadow_rays: s.candidate_shadow_rays,
                    light_bvh: s.light_sampler == LightSampler::Bvh,
                },
                shared.accumulation,
            )
        })?;
        if s.temporal {
            let history = match (frame, &self.previous) {
                (0, Some(previous)) => TemporalHistory::Animation(previous),
                (0, None) => TemporalHistory::None,
                _ => TemporalHistory::Render,
            };
            let options = TemporalOptions {
                cap: match (frame, self.lights_changed) {
                    (0, true) => s.relit_cap,
                    _ => s.temporal_cap,
                },
                combination: s.combination,
                normal_cos: s.temporal_normal,
                depth_tolerance: s.temporal_depth,
            };
            cmd.pass("restir temporal", |cmd| {
                restir
                    .temporal
                    .record(cmd, &inputs, history, options, shared.accumulation)
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

    /// Stats over the pixels that see a surface (a final reservoir with M > 0) in the last
    /// frame: the fraction whose final sample is a visible light (W > 0) and the mean confidence
    /// M, which temporal reuse grows to its cap.
    fn finish(&self, _shared: &Shared<'_>) -> GpuResult<Extras> {
        // (Read before the render is marked finished: a failed readback leaves no history.)
        let reservoirs = self
            .reservoirs
            .as_ref()
            .expect("held until dropped")
            .read_final()?;
        self.finished.set(true);
        let surfaces: Vec<_> = reservoirs.iter().filter(|r| r.weights.y > 0.0).collect();
        let n = surfaces.len().max(1) as f64;
        let lit = surfaces.iter().filter(|r| r.weights.x > 0.0).count() as f64;
        let mean_m = surfaces.iter().map(|r| f64::from(r.weights.y)).sum::<f64>() / n;
        Ok(Extras {
            stats: vec![
                ("final_visible_fraction".into(), lit / n),
                ("final_mean_m".into(), mean_m),
            ],
            ..Extras::default()
        })
    }
}

impl Drop for RestirFrames<'_> {
    /// A completed render's final reservoirs become the history the next render may reuse.
    fn drop(&mut self) {
        if !self.finished.get() {
            return;
        }
        if let Some(reservoirs) = self.reservoirs.take() {
            *self.restir.history.borrow_mut() = Some(History {
                frame: self.frame,
                content_hash: self.content_hash,
                camera: self.camera,
                size: self.size,
                reservoirs,
                light_keys: std::mem::take(&mut self.light_keys),
            });
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The candidate kernel lays out its random-number dimensions and its streams' registers
    /// for the settings' maxima: raising one in Rust alone would overlap dimensions or cap T.
    #[test]
    fn the_candidate_kernel_is_laid_out_for_the_settings_maxima() {
        let glsl = include_str!("../../../glsl/restir/generate_restir_candidates.comp");
        for line in [
            format!("const uint BSDF_DIMENSIONS = 16u + 8u * {MAX_CANDIDATES}u;"),
            format!(
                "const uint STREAM_DIMENSIONS = BSDF_DIMENSIONS + 8u * {MAX_BSDF_CANDIDATES}u;"
            ),
            format!("const uint MAX_STREAMS = {MAX_CANDIDATE_SHADOW_RAYS}u;"),
        ] {
            assert!(glsl.contains(&line), "{line}");
        }
    }
}
