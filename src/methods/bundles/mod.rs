//! Real-time bidirectional path tracing (Tokuyoshi 12), method `bundles`: per frame, the
//! G-buffer and direct light of the point and spot lights by next-event estimation (as the
//! reference: one light per sample, the environment's entry left out),
//! then I iterations (the paper's 21), each with one VPL per light, or from one light by
//! Russian roulette (light_vertices), and one global ray bundle from the visible points
//! (ray_bundles, directions drawn by directions), whose escaping rays estimate the
//! environment map's direct light, whose one-bounce paths are combined with the VPLs' by MIS
//! and whose two-bounce paths share the edge between a VPL and the bundle hit (paths). irad
//! traces the bundles through the BVH where the paper rasterizes them into per-pixel linked
//! lists: the same rays, exact visibility.

pub mod directions;
pub mod light_vertices;
pub mod paths;
pub mod ray_bundles;

use std::mem::size_of;

use crate::gpu::{Buffer, Commands, Context, GpuResult};
use crate::methods::across_frames::{AcrossFrames, AnimationFrame};
use crate::methods::compensation::ClampSettings;
use crate::methods::device_fit;
use crate::methods::direct::{DirectLightOptions, DirectLightPaths};
use crate::methods::driver::{Extras, MethodFrames, Shared};
use crate::methods::gbuffer::PixelSampling;
use crate::methods::interface::{Lights, RenderMethod, SharedPasses, Support};
use crate::methods::lights::NO_LUMINAIRES;
use crate::methods::rebuild::TableRebuild;
use crate::methods::settings::{
    common_settings, field_setting, named_choices, Kind, Need, Setting, Value,
};
use crate::sampling::environment::sampling_weights;
use crate::sampling::pcg;
use crate::scene::gpu::GpuScene;
use crate::scene::Scene;

use directions::{BundleDirections, DirectionDensity};
use light_vertices::{FrameLightVertices, LightSelection, TraceLightVertices};
use paths::{Chunk, ShadeBundlePaths, Shading};
use ray_bundles::{BundleHit, TraceRayBundles};

/// Which one-bounce paths are shaded.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Strategy {
    /// Through the VPLs only (instant radiosity's one bounce).
    Vpl,
    /// Through the bundle hits only (one-bounce path tracing along shared directions).
    Bundle,
    /// Both, weighted by the power heuristic (Eq. 3-6).
    Mis,
}

// In the order of glsl/bundles/shade_bundle_paths.comp's STRATEGY_* codes (`Strategy as u32`).
named_choices!(Strategy {
    Vpl => "vpl",
    Bundle => "bundle",
    Mis => "mis",
});

/// Glossy spike suppression of the one-bounce paths (Tokuyoshi 12 Section 5): each a named,
/// measured bias.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Suppression {
    None,
    /// Clamp the Phong exponent per sample by the density of samples around it (Eq. 9-17),
    /// with the paper's m' (16).
    Roughness {
        m_prime: f32,
    },
    /// Clamp each path's weighted contribution at this value (largest channel).
    Contribution {
        max: f32,
    },
}

impl Suppression {
    pub fn name(self) -> &'static str {
        match self {
            Suppression::None => "none",
            Suppression::Roughness { .. } => "roughness",
            Suppression::Contribution { .. } => "clamp",
        }
    }
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BundlesSettings {
    /// I: VPLs and bundles per frame (one of each per iteration).
    pub iterations: u32,
    pub frames: u32,
    pub seed: u32,
    pub strategy: Strategy,
    /// The power heuristic's exponent: 1 is the balance heuristic (the paper's), 2 Veach's
    /// power heuristic.
    pub beta: f32,
    /// Shade the two-bounce paths (x0, x1, x2, x3).
    pub two_bounce: bool,
    /// Clamp of their x1-x2 geometry term (the paper's, there a named bias) and whether what
    /// it removed is added back by a short path from x2 (Kollig and Keller 2004), so the clamp
    /// removes the spikes without the bias (default). Auto: b = N / A as ir's gather
    /// (compensation.rs), N the light vertices per frame.
    pub two_bounce_clamp: ClampSettings,
    pub suppression: Suppression,
    /// Which lights each iteration's VPLs leave from.
    pub lights: LightSelection,
    /// The bundles' direction density: Environment (Eq. 2) applies to scenes with a map.
    pub directions: DirectionDensity,
    /// Eq. 2's Lo (luminance); None: 0 when the map is the only light, else the map's mean
    /// luminance, so bundle rays still cover the directions the map leaves dark.
    pub env_offset: Option<f32>,
    /// The direction table (pass "bundle directions"): once for a still map, per frame for a
    /// sequence (default), or every frame.
    pub rebuild: TableRebuild,
    /// Direct-light samples per pixel and frame, each from its own camera ray (new subpixel
    /// position), so direct light and the pixel footprint get this many samples while the
    /// expensive indirect estimate gets one position per frame (`--direct-spp`).
    pub direct_spp: u32,
    pub pixels: PixelSampling,
}

impl Default for BundlesSettings {
    fn default() -> Self {
        BundlesSettings {
            iterations: 21,
            frames: 16,
            seed: 0,
            strategy: Strategy::Mis,
            beta: 1.0,
            two_bounce: true,
            two_bounce_clamp: ClampSettings::default(),
            suppression: Suppression::Roughness {
                m_prime: ROUGHNESS_M,
            },
            lights: LightSelection::All,
            directions: DirectionDensity::Environment,
            env_offset: None,
            rebuild: TableRebuild::WhenChanged,
            // Point and spot lights' next-event estimate has no light-sampling noise, so
            // only the pixel footprint gains (measured, spot-light 128x128, 2 seeds,
            // lavapipe: relMSE 2.645e-4 at 1 direct sample, 2.609e-4 at 32; glossy-cornell
            // 4.382e-2 and 4.381e-2): direct light and footprint are 1.4% of the error at 1.
            direct_spp: 1,
            pixels: PixelSampling::Jittered,
        }
    }
}

/// `glossy = "roughness"`'s m' where `roughness_m` does not set it (the paper's).
pub const ROUGHNESS_M: f32 = 16.0;
/// `glossy = "clamp"`'s largest channel where `contribution_clamp` does not set it.
pub const CONTRIBUTION_CLAMP: f32 = 1.0;

/// Global ray bundles' settings (`irad methods bundles`).
pub const SETTINGS: &[Setting<BundlesSettings>] = &[
    field_setting!(
        "iterations",
        iterations,
        Kind::Count {
            min: 1,
            max: 1 << 16
        },
        Count,
        "Iterations per frame, each one VPL and one global ray bundle (the paper's 21).",
    ),
    common_settings!(
        frames,
        "Frames, each with fresh VPLs, bundles and subpixel positions."
    ),
    common_settings!(seed),
    Setting::new(
        "strategy",
        Kind::Choice(Strategy::NAMES),
        "Which one-bounce paths: through the VPLs (vpl), through the ray bundles (bundle), or \
         both combined by MIS (mis).",
        |s| Some(Value::Name(s.strategy.name())),
        |s, v| {
            s.strategy = Strategy::from_name(v.name()).expect("a checked name");
        },
    ),
    Setting::<BundlesSettings>::new(
        "heuristic",
        Kind::Choice(&["balance", "power"]),
        "The MIS weights of the one-bounce paths: the balance heuristic (the paper's) or the \
         power heuristic (exponent 2).",
        |s| Some(Value::Name(if s.beta == 1.0 { "balance" } else { "power" })),
        |s, v| s.beta = if v.name() == "power" { 2.0 } else { 1.0 },
    )
    // The weights combine the two strategies of mis.
    .needs(&[Need::OneOf("strategy", &["mis"])]),
    field_setting!(
        "two_bounce",
        two_bounce,
        Kind::Switch,
        Switch,
        "Shade the two-bounce paths (x0, x1, x2, x3) through the VPL-to-bundle-hit edge \
         (Tokuyoshi Eq. 7-8).",
    ),
    Setting::<BundlesSettings>::new(
        "two_bounce_clamp",
        Kind::Clamp,
        "Clamp the two-bounce paths' x1-x2 geometry term cos cos / d^2 at b (the paper's \
         clamp, 10 there; compensated unless compensate is false, else a bias). auto: b = N / \
         A for N light vertices per frame over the scene's area A, as ir's clamp; a number \
         sets b; 0 leaves the term unclamped. The b used is in the JSON's stats.",
        |s| {
            s.two_bounce
                .then_some(Value::Clamp(s.two_bounce_clamp.clamp))
        },
        |s, v| s.two_bounce_clamp.clamp = v.clamp(),
    )
    .unset("auto (with two_bounce)")
    .needs(&[Need::OneOf("two_bounce", &["true"])]),
    Setting::<BundlesSettings>::new(
        "compensate",
        Kind::Switch,
        "With two_bounce_clamp, add back exactly what it removed by short paths from the \
         bundle hit x2 (Kollig and Keller 2004; unbiased), or leave the clamp's bias (false).",
        |s| {
            s.two_bounce
                .then_some(Value::Switch(s.two_bounce_clamp.compensate))
        },
        |s, v| s.two_bounce_clamp.compensate = v.switch(),
    )
    .unset("true (with two_bounce)")
    .needs(&[
        Need::OneOf("two_bounce", &["true"]),
        Need::Not("two_bounce_clamp", "0"),
    ]),
    Setting::new(
        "glossy",
        Kind::Choice(&["none", "roughness", "clamp"]),
        "Glossy spike suppression of the one-bounce paths (Tokuyoshi Section 5, each a named \
         bias): clamp the Phong exponent per sample by the density of samples around it \
         (roughness), clamp each path's contribution (clamp), or none.",
        |s| Some(Value::Name(s.suppression.name())),
        |s, v| {
            s.suppression = match v.name() {
                "none" => Suppression::None,
                "clamp" => Suppression::Contribution {
                    max: CONTRIBUTION_CLAMP,
                },
                _ => Suppression::Roughness {
                    m_prime: ROUGHNESS_M,
                },
            };
        },
    ),
    Setting::<BundlesSettings>::new(
        "roughness_m",
        Kind::Number,
        "With glossy roughness: the paper's m' (neighbours per kernel; larger blurs more).",
        |s| match s.suppression {
            Suppression::Roughness { m_prime } => Some(Value::Number(m_prime)),
            _ => None,
        },
        |s, v| {
            if let Suppression::Roughness { m_prime } = &mut s.suppression {
                *m_prime = v.number();
            }
        },
    )
    .unset("16 (with glossy roughness)")
    .needs(&[Need::OneOf("glossy", &["roughness"])]),
    Setting::<BundlesSettings>::new(
        "contribution_clamp",
        Kind::Number,
        "With glossy clamp: the largest channel a path's contribution may have.",
        |s| match s.suppression {
            Suppression::Contribution { max } => Some(Value::Number(max)),
            _ => None,
        },
        |s, v| {
            if let Suppression::Contribution { max } = &mut s.suppression {
                *max = v.number();
            }
        },
    )
    .unset("1 (with glossy clamp)")
    .needs(&[Need::OneOf("glossy", &["clamp"])]),
    Setting::new(
        "lights",
        Kind::Choice(LightSelection::NAMES),
        "The lights each iteration's VPLs leave from: one VPL from every point and spot light \
         (all, the paper's default), or one light chosen by power (roulette, for many lights; \
         Tokuyoshi Section 4.1).",
        |s| Some(Value::Name(s.lights.name())),
        |s, v| {
            s.lights = LightSelection::from_name(v.name()).expect("a checked name");
        },
    ),
    Setting::new(
        "directions",
        Kind::Choice(DirectionDensity::NAMES),
        "The density of the bundle directions: uniform on the sphere, or, in a scene with an \
         environment map, Tokuyoshi's Eq. 2 (Le(w) + Le(-w) + 2 Lo), which importance samples \
         the map's direct light (environment; uniform where there is no map).",
        |s| Some(Value::Name(s.directions.name())),
        |s, v| {
            s.directions = DirectionDensity::from_name(v.name()).expect("a checked name");
        },
    ),
    Setting::<BundlesSettings>::new(
        "env_offset",
        Kind::Number,
        "With directions environment: Eq. 2's offset Lo (luminance) for the indirect light \
         the map does not show.",
        |s| s.env_offset.map(Value::Number),
        |s, v| s.env_offset = Some(v.number()),
    )
    .unset("0 when the map is the only light, else the map's mean luminance")
    .needs(&[Need::OneOf("directions", &["environment"])]),
    // The only table is the environment direction density's.
    common_settings!(rebuild_tables, needs: &[Need::OneOf("directions", &["environment"])]),
    common_settings!(direct_spp),
    common_settings!(pixel_centres),
];

/// Bundle hits kept at once: the iterations of a frame are traced and shaded in chunks that
/// fit (a chunk is at least one iteration).
const HIT_BYTES: usize = 64 << 20;

/// Most chunks per frame, so a submission of 16 frames stays within the 512 timed passes.
const MAX_CHUNKS: u32 = 12;

pub struct Bundles {
    light_vertices: TraceLightVertices,
    ray_bundles: TraceRayBundles,
    paths: ShadeBundlePaths,
}

impl Bundles {
    /// Eq. 2's Lo when none is given: 0 when the map is the only light (its direct light is
    /// all the bundles carry), else the map's mean luminance over the sphere, so every bundle
    /// direction keeps at least half the uniform density for the lights' indirect paths.
    pub fn default_env_offset(scene: &Scene) -> f32 {
        match &scene.environment {
            Some(env) if !scene.lights.is_empty() => {
                let total: f64 = sampling_weights(env).iter().sum();
                (total / (4.0 * std::f64::consts::PI)) as f32
            }
            _ => 0.0,
        }
    }

    /// Iterations traced and shaded together at this pixel count.
    pub fn chunk_size(iterations: u32, pixels: usize) -> u32 {
        let fits = (HIT_BYTES / (pixels.max(1) * std::mem::size_of::<BundleHit>())) as u32;
        fits.clamp(iterations.div_ceil(MAX_CHUNKS), iterations.max(1))
    }
}

impl RenderMethod for Bundles {
    type Settings = BundlesSettings;
    const NAME: &'static str = "bundles";
    const SUMMARY: &'static str =
        "Real-time bidirectional path tracing (Tokuyoshi 12): VPLs and global ray bundles \
         combined by MIS, for point and spot lights.";
    const SETTINGS: &'static [Setting<BundlesSettings>] = SETTINGS;
    const COUNT: &'static str = "frames";
    const LIGHTS: Lights = Lights {
        environment: Support::Renders,
        area: Support::Declines("Tokuyoshi 12 Section 4 starts VPLs from point lights"),
        point: Support::Renders,
        luminaires: Support::Declines(NO_LUMINAIRES),
    };
    const ACROSS_FRAMES: AcrossFrames = AcrossFrames::NOTHING;

    fn new(ctx: &Context) -> GpuResult<Self> {
        Ok(Bundles {
            light_vertices: TraceLightVertices::new(ctx)?,
            ray_bundles: TraceRayBundles::new(ctx)?,
            paths: ShadeBundlePaths::new(ctx)?,
        })
    }

    /// The environment's direct light is the bundles' own.
    fn shared_passes(settings: &BundlesSettings) -> SharedPasses {
        SharedPasses {
            pixels: settings.pixels,
            direct: Some(DirectLightOptions {
                light: DirectLightPaths::NextEvent,
                reflected_environment: false,
                spp: settings.direct_spp,
            }),
        }
    }

    fn work(s: &BundlesSettings) -> f64 {
        s.frames as f64 * s.iterations as f64
    }

    fn fits(s: &BundlesSettings, scene: &Scene, limit: u64) -> Result<(), String> {
        // BundleHits: a chunk of iterations' hits per pixel (set_up); the frame's light
        // vertices: iterations x slots (light_vertices.rs).
        let pixels = scene.camera.width as u64 * scene.camera.height as u64;
        let slots = match s.lights {
            LightSelection::All => scene.lights.len().max(1) as u64,
            LightSelection::Roulette => 1,
        };
        let bytes = |iterations: u64| {
            let hits = Self::chunk_size(iterations as u32, pixels as usize) as u64
                * pixels
                * size_of::<BundleHit>() as u64;
            hits.max(iterations * slots * size_of::<light_vertices::LightVertex>() as u64)
        };
        let n = s.iterations as u64;
        let (w, h) = (scene.camera.width, scene.camera.height);
        device_fit::check_size(n, limit, bytes, |over, largest| {
            format!(
                "bundles: iterations = {n} (--iterations): the bundles' hits at {w}x{h} pixels \
                 {over}; the largest that fits is {largest}"
            )
        })
    }

    /// The render's light vertices, bundle directions, hits and shading settings.
    fn set_up<'a>(
        &'a self,
        ctx: &Context,
        scene: &Scene,
        gpu_scene: &GpuScene,
        settings: &'a BundlesSettings,
        _animation: &AnimationFrame<'_>,
    ) -> GpuResult<Box<dyn MethodFrames + 'a>> {
        let per_frame = settings.iterations.max(1);
        let chunk = Self::chunk_size(per_frame, gpu_scene.pixel_count());
        let vertices = FrameLightVertices::new(ctx, gpu_scene, per_frame, settings.lights)?;
        let offset = settings
            .env_offset
            .unwrap_or_else(|| Self::default_env_offset(scene));
        let directions = BundleDirections::new(ctx, gpu_scene, settings.directions, offset)?;
        let hits = Buffer::zeroed(ctx, "BundleHits", chunk as usize * gpu_scene.pixel_count())?;
        let environment = gpu_scene.environment_size.is_some();
        let shading = Shading {
            strategy: settings.strategy,
            beta: settings.beta,
            two_bounce: settings.two_bounce.then(|| {
                settings
                    .two_bounce_clamp
                    .resolve(scene, per_frame * vertices.slots)
            }),
            // Without point or spot lights there is no two-bounce light to compensate.
            compensate: settings.two_bounce_clamp.compensate && vertices.lights > 0,
            seed: pcg::hash(&[settings.seed, 0x62636d70]),
            suppression: settings.suppression,
            environment,
        };
        Ok(Box::new(BundlesFrames {
            bundles: self,
            settings,
            per_frame,
            chunk,
            vertices,
            offset,
            directions,
            hits,
            seed: pcg::hash(&[settings.seed, 0x62756e64]),
            environment,
            shading,
            // The VPL paths alone need no bundle hits (the shading kernel then reads none).
            trace_bundles: settings.strategy != Strategy::Vpl || settings.two_bounce || environment,
        }))
    }
}

/// One bundles render's light vertices, directions and hits.
struct BundlesFrames<'a> {
    bundles: &'a Bundles,
    settings: &'a BundlesSettings,
    per_frame: u32,
    chunk: u32,
    vertices: FrameLightVertices,
    offset: f32,
    directions: BundleDirections,
    hits: Buffer<BundleHit>,
    seed: u32,
    environment: bool,
    shading: Shading,
    trace_bundles: bool,
}

impl MethodFrames for BundlesFrames<'_> {
    fn record<'a>(
        &'a self,
        shared: &Shared<'a>,
        cmd: &mut Commands<'a>,
        frame: u32,
    ) -> GpuResult<()> {
        let (bundles, settings, gpu_scene) = (self.bundles, self.settings, shared.scene);
        let (per_frame, chunk) = (self.per_frame, self.chunk);
        let frames = settings.frames.max(1);
        if self.environment
            && self.directions.density() == DirectionDensity::Environment
            && settings
                .rebuild
                .due(frame, gpu_scene.environment_frames() > 1)
        {
            cmd.pass("bundle directions", |cmd| {
                self.directions.record(cmd, gpu_scene)
            })?;
        }
        let first = frame * per_frame;
        cmd.pass("light vertices", |cmd| {
            bundles.light_vertices.record(
                cmd,
                gpu_scene,
                &self.vertices,
                &self.directions,
                first,
                self.seed,
            )
        })?;
        let mut index = 0;
        while index < per_frame {
            let count = chunk.min(per_frame - index);
            if self.trace_bundles {
                cmd.pass("ray bundles", |cmd| {
                    bundles.ray_bundles.record(
                        cmd,
                        gpu_scene,
                        shared.gbuffer,
                        &self.vertices,
                        &self.hits,
                        index,
                        count,
                    )
                })?;
            }
            let c = Chunk {
                first_index: index,
                count,
                per_frame,
                samples: per_frame * frames,
                traced: self.trace_bundles,
                frame_first: first,
            };
            cmd.pass("bundle paths", |cmd| {
                bundles.paths.record(
                    cmd,
                    gpu_scene,
                    shared.gbuffer,
                    &self.vertices,
                    &self.directions,
                    &self.hits,
                    shared.accumulation,
                    &c,
                    &self.shading,
                )
            })?;
            index += count;
        }
        Ok(())
    }

    fn finish(&self, shared: &Shared<'_>) -> GpuResult<Extras> {
        let (settings, shading) = (self.settings, &self.shading);
        let pixels = shared.scene.pixel_count() as f64;
        // Per iteration: each light vertex's ray, and per pixel the bundle ray and, per light
        // vertex, at most three shadow rays (to x1, from x2 to the light, and x1-x2 for two
        // bounces); the two-bounce compensation adds per pixel one ray from x2 and, per light
        // vertex, at most one shadow ray.
        let slots = self.vertices.slots as f64;
        let compensated = shading.two_bounce.is_some_and(|b| b > 0.0) && shading.compensate;
        let shadow_rays = match settings.strategy {
            Strategy::Vpl | Strategy::Bundle => 1.0,
            Strategy::Mis => 2.0,
        } + if settings.two_bounce { 1.0 } else { 0.0 }
            + if compensated { 1.0 } else { 0.0 };
        Ok(Extras {
            stats: vec![
                ("iterations_per_chunk".into(), self.chunk as f64),
                ("light_vertices_per_iteration".into(), slots),
                ("bundle_env_offset".into(), self.offset as f64),
                // The two-bounce edge's b (0: unclamped or no two-bounce paths).
                (
                    "two_bounce_clamp".into(),
                    shading.two_bounce.unwrap_or(0.0) as f64,
                ),
                (
                    "rays_per_iteration_max".into(),
                    slots + pixels * (1.0 + compensated as u32 as f64 + slots * shadow_rays),
                ),
            ],
            maps: vec![],
        })
    }
}
