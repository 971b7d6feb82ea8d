//! Dynamic environment-map importance sampling (Lu 14 ch. 3), method `env`: per frame the
//! G-buffer (and the map the camera sees directly), the cube-map sampling table rebuilt from
//! the scene's map on the GPU (cube: weights, scans, the frame's light samples per face), and
//! the direct light of the map with visibility by the chosen strategy (shade).

pub mod cube;
pub mod pyramid;
pub mod shade;

use std::mem::size_of;

use crate::gpu::{Buffer, Commands, Context, GpuResult};
use crate::image::Image;
use crate::methods::across_frames::{AcrossFrames, AnimationFrame};
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
use crate::sampling::pcg;
use crate::scene::gpu::GpuScene;
use crate::scene::Scene;

use crate::methods::equirect_table::EquirectTable;
use cube::CubeTable;
use pyramid::EnvPyramid;
use shade::ShadeEnv;

/// How the map's direct light is sampled.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Strategy {
    /// Lu's method: per-pixel face shares mu_f(n) (Eq. 3.4), fractional counts with beta
    /// weights (Eq. 3.5-3.6), half the samples from the BRDF, balance heuristic (Eq. 3.7).
    Dynamic,
    /// The same with mu_f = 1/6 (the thesis's baseline, Fig. 3.6).
    UniformFaces,
    /// BRDF sampling only.
    Brdf,
    /// Cosine-weighted hemisphere sampling only.
    Cosine,
    /// Half the samples from one table over the whole equirectangular map (luminance times
    /// solid angle: pbrt's and Mitsuba's sampler), half from the BRDF, balance heuristic.
    Latlong,
    /// As latlong, with a luminance mip pyramid descended 2x2 per level instead of a CDF
    /// (Falcor's and Mitsuba 3's sampler).
    Hierarchical,
    /// dynamic's two samplers split per pixel by Lu 14 Chapter 5: M samples half and half
    /// estimate the BRDF share alpha (Eq. 5.4-5.5), the other N use it, Eq. 5.6 combines them.
    Alpha,
}

// In the order of glsl/envmap/shade_env.comp's STRATEGY_* codes (`code`).
named_choices!(Strategy {
    Dynamic => "dynamic",
    UniformFaces => "uniform-faces",
    Brdf => "brdf",
    Cosine => "cosine",
    Latlong => "latlong",
    Hierarchical => "hierarchical",
    Alpha => "alpha",
});

impl Strategy {
    /// The strategy codes of glsl/envmap/shade_env.comp: the declaration order (a unit test checks
    /// the GLSL's defines).
    pub fn code(self) -> u32 {
        self as u32
    }

    /// Whether the strategy samples the cube map (and so needs its table).
    pub fn uses_cube(self) -> bool {
        matches!(
            self,
            Strategy::Dynamic | Strategy::UniformFaces | Strategy::Alpha
        )
    }
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EnvSettings {
    /// N_s: samples per pixel per frame (light and BRDF together).
    pub spp: u32,
    pub frames: u32,
    pub seed: u32,
    pub strategy: Strategy,
    /// R: texels along a cube face's side.
    pub face_resolution: u32,
    /// dynamic and uniform-faces: every sample from the cube map (Eq. 3.5, the thesis's
    /// Fig. 3.6 comparison) instead of half from the BRDF (Eq. 3.7).
    pub light_only: bool,
    /// dynamic and uniform-faces: round(M_f) light samples per face, each of weight 1 (the
    /// thesis's "classical integer number of samples", Fig. 3.9) instead of the beta weights;
    /// still unbiased under Eq. 3.7 (the BRDF samples cover a face rounded to none), not with
    /// light samples only.
    pub integer_counts: bool,
    /// alpha: M, the samples per pixel and frame that estimate alpha (the rest, N_s - M, use
    /// it); None: N_s / 2 (Lu's Table 5.2 setting).
    pub alpha_samples: Option<u32>,
    /// A shadow ray per sample (true, the default). false leaves visibility out, as the
    /// thesis's timings do: for timing comparisons only, the image is wrong where occluded.
    pub shadows: bool,
    /// The cube map, its CDFs, the latitude-longitude table and the pyramid: once for a still
    /// map, per frame for a sequence (default), or every frame (Lu's pipeline, for timing).
    pub rebuild: TableRebuild,
    /// Lu's one set of light samples per face and frame shared by every pixel (true), instead
    /// of a window per pixel out of SAMPLE_WINDOWS (the default, whose image error does not
    /// move as one).
    pub shared_samples: bool,
    pub pixels: PixelSampling,
}

impl Default for EnvSettings {
    fn default() -> Self {
        EnvSettings {
            spp: 60,
            frames: 16,
            seed: 0,
            strategy: Strategy::Dynamic,
            face_resolution: 256,
            light_only: false,
            integer_counts: false,
            alpha_samples: None,
            shadows: true,
            rebuild: TableRebuild::WhenChanged,
            shared_samples: false,
            pixels: PixelSampling::Jittered,
        }
    }
}

/// The strategies that sample the cube map (`Strategy::uses_cube`), where its settings apply.
pub const CUBE_STRATEGIES: &[&str] = &["dynamic", "uniform-faces", "alpha"];
/// The strategies that take a fixed share of light samples split by the face shares, where
/// light_only and integer_counts apply.
pub const FACE_SHARE_STRATEGIES: &[&str] = &["dynamic", "uniform-faces"];

/// Environment-map direct light's settings (`irad methods env`).
pub const SETTINGS: &[Setting<EnvSettings>] = &[
    field_setting!(
        "spp",
        spp,
        Kind::Count {
            min: 1,
            max: 1 << 16
        },
        Count,
        "N_s: samples per pixel and frame, light and BRDF samples together.",
    ),
    common_settings!(
        frames,
        "Frames, each with fresh light samples and subpixel positions."
    ),
    common_settings!(seed),
    Setting::new(
        "strategy",
        Kind::Choice(Strategy::NAMES),
        "How the map's light is sampled: dynamic (Lu 14 ch. 3: per-pixel face shares, \
         fractional counts, MIS with BRDF sampling), uniform-faces (the same with every face \
         getting 1/6 of the light samples), brdf or cosine (no light samples), latlong (one \
         table over the whole map, as pbrt and Mitsuba; MIS with BRDF), hierarchical (a \
         luminance mip pyramid descended 2x2 per level, as Falcor and Mitsuba 3; MIS with \
         BRDF), alpha (dynamic's samplers split per pixel by Lu 14 ch. 5's estimated alpha; \
         writes OUT.alpha.{exr,png}: red light samples, green BRDF samples). At equal time \
         (docs/RESULTS.md \"env: strategies at equal time\"): dynamic wins by 2.2-2.9x over \
         latlong on sun-behind; latlong by \
         1.4x on glossy geometry under an open sky (glossy-env) and 1.5x on the dynamic \
         moving-sun. Per frame of a dynamic sky at equal frame time (scenes/suites/realtime.toml: \
         moving-sun-sequence and rising-sun-sequence, 64x48, 8 samples a frame, 13 and 52 ms \
         a frame): latlong wins (relMSE x frame time 0.166 and 0.070 on the rising sun, \
         hierarchical 1.04-1.12x behind; on the turning sun the two tie, 1.03 and 0.665 \
         against 1.04 and 0.651, and their order changes between runs), dynamic 17-90x \
         behind on lavapipe: its cube map and tables, rebuilt from every frame's map, take \
         about 100 ms a frame there.",
        |s| Some(Value::Name(s.strategy.name())),
        |s, v| {
            s.strategy = Strategy::from_name(v.name()).expect("a checked name");
        },
    ),
    field_setting!(
        "face_resolution",
        face_resolution,
        Kind::Count { min: 1, max: 4096 },
        Count,
        "Texels along a side of each face of the cube map that drives the light samples.",
        needs: &[Need::OneOf("strategy", CUBE_STRATEGIES)],
    ),
    field_setting!(
        "light_only",
        light_only,
        Kind::Switch,
        Switch,
        "With strategy dynamic or uniform-faces: take every sample from the cube map (Lu Eq. \
         3.5, the thesis's Fig. 3.6 setting) instead of half from the BRDF (Eq. 3.7).",
        needs: &[Need::OneOf("strategy", FACE_SHARE_STRATEGIES)],
    ),
    field_setting!(
        "integer_counts",
        integer_counts,
        Kind::Switch,
        Switch,
        "With strategy dynamic or uniform-faces: round(M_f) light samples per face, each of \
         weight 1, instead of the beta weights (the thesis's integer counts, Fig. 3.9).",
        needs: &[Need::OneOf("strategy", FACE_SHARE_STRATEGIES)],
    ),
    Setting::<EnvSettings>::new(
        "alpha_samples",
        Kind::Count {
            min: 0,
            max: 1 << 16,
        },
        "With strategy alpha: M, the samples per pixel and frame, half light and half BRDF, \
         that estimate the per-pixel split alpha (Lu 14 Eq. 5.4-5.5); the other spp minus M \
         use it.",
        |s| s.alpha_samples.map(Value::Count),
        |s, v| s.alpha_samples = Some(v.count()),
    )
    .unset("half of spp")
    // M of the spp samples.
    .needs(&[Need::OneOf("strategy", &["alpha"]), Need::AtMost("spp")]),
    common_settings!(shadows),
    field_setting!(
        "shared_samples",
        shared_samples,
        Kind::Switch,
        Switch,
        "Every pixel takes the frame's one set of light samples per face (Lu's) instead of \
         its own window of a 64 times longer sequence (the whole image's error then moves as \
         one).",
        needs: &[Need::OneOf("strategy", CUBE_STRATEGIES)],
    ),
    // brdf and cosine build no table.
    common_settings!(rebuild_tables, needs: &[Need::OneOf(
        "strategy",
        &["dynamic", "uniform-faces", "latlong", "hierarchical", "alpha"],
    )]),
    common_settings!(pixel_centres),
];

/// Windows of light samples per face and frame that pixels pick from (unless shared).
pub const SAMPLE_WINDOWS: u32 = 64;
/// Most light samples a frame generates over its windows (16 MiB of samples).
pub const MAX_WINDOWED_SAMPLES: u32 = 1 << 20;

pub struct Env {
    shade: ShadeEnv,
}

/// Why env declines a scene with lights besides the map.
const MAP_ONLY: &str = "it shades the environment map's direct light only";

impl RenderMethod for Env {
    type Settings = EnvSettings;
    const NAME: &'static str = "env";
    const SUMMARY: &'static str =
        "Environment-map direct light with per-pixel dynamic cube-map sampling (Lu 14 ch. 3).";
    const SETTINGS: &'static [Setting<EnvSettings>] = SETTINGS;
    const COUNT: &'static str = "frames";
    const LIGHTS: Lights = Lights {
        environment: Support::Needs("it renders an environment map's direct light"),
        area: Support::Declines(MAP_ONLY),
        point: Support::Declines(MAP_ONLY),
        luminaires: Support::Declines(NO_LUMINAIRES),
    };
    const ACROSS_FRAMES: AcrossFrames = AcrossFrames::NOTHING;

    fn new(ctx: &Context) -> GpuResult<Self> {
        Ok(Env {
            shade: ShadeEnv::new(ctx)?,
        })
    }

    /// The G-buffer and the emission the camera sees (the map behind the scene).
    fn shared_passes(settings: &EnvSettings) -> SharedPasses {
        SharedPasses {
            pixels: settings.pixels,
            direct: Some(DirectLightOptions {
                light: DirectLightPaths::EmissionOnly,
                reflected_environment: true,
                spp: 0,
            }),
        }
    }

    fn work(s: &EnvSettings) -> f64 {
        s.frames as f64 * s.spp as f64
    }

    fn fits(s: &EnvSettings, _scene: &Scene, limit: u64) -> Result<(), String> {
        // CubeWeights and CubeRowCdf: 6 R^2 f32s (cube.rs). The strategies' light samples are
        // bounded by MAX_WINDOWED_SAMPLES whatever spp is.
        let bytes = |r: u64| 6 * r * r * size_of::<f32>() as u64;
        let r = s.face_resolution as u64;
        device_fit::check_size(r, limit, bytes, |over, largest| {
            format!(
                "env: face_resolution = {r} (--face-resolution): the cube map's table {over}; \
                 the largest that fits is {largest}"
            )
        })
    }

    /// The render's sampling tables (cube map, latitude-longitude, pyramid) and per-pixel
    /// counts.
    fn set_up<'a>(
        &'a self,
        ctx: &Context,
        _scene: &Scene,
        gpu_scene: &GpuScene,
        settings: &'a EnvSettings,
        _animation: &AnimationFrame<'_>,
    ) -> GpuResult<Box<dyn MethodFrames + 'a>> {
        let spp = settings.spp.max(1);
        let strategy = settings.strategy;
        let light_only =
            settings.light_only && matches!(strategy, Strategy::Dynamic | Strategy::UniformFaces);
        let alpha_samples = settings.alpha_samples.unwrap_or(spp / 2).min(spp);
        // Samples per face: the light share of N_s, or for alpha the larger of its two steps'
        // (M / 2 from set 0; at most N from set 1).
        let (per_face, sets) = match strategy {
            Strategy::Alpha => ((alpha_samples.div_ceil(2)).max(spp - alpha_samples), 2),
            _ if light_only => (spp, 1),
            _ => (spp.div_ceil(2), 1),
        };
        // Fewer windows where a frame's samples would pass MAX_WINDOWED_SAMPLES (a huge N_s),
        // none for the strategies that draw nothing from the cube map.
        let windows = if settings.shared_samples || !strategy.uses_cube() {
            1
        } else {
            (MAX_WINDOWED_SAMPLES / (6 * sets * per_face).max(1)).clamp(1, SAMPLE_WINDOWS)
        };
        let pixels = gpu_scene.pixel_count();
        Ok(Box::new(EnvFrames {
            env: self,
            settings,
            spp,
            light_only,
            alpha_samples,
            cube: CubeTable::new(ctx, settings.face_resolution, per_face, sets, windows)?,
            seed: pcg::hash(&[settings.seed, 0x656e76]),
            counts: Buffer::zeroed(ctx, "EnvSampleCounts", pixels)?,
            alpha: Buffer::zeroed(ctx, "EnvAlpha", pixels)?,
            alpha_terms: Buffer::zeroed(
                ctx,
                "EnvAlphaTerms",
                if strategy == Strategy::Alpha {
                    pixels
                } else {
                    1
                },
            )?,
            latlong: EquirectTable::new(ctx, gpu_scene, 0.0, strategy == Strategy::Latlong)?,
            pyramid: EnvPyramid::new(ctx, gpu_scene, strategy == Strategy::Hierarchical)?,
            sequence: gpu_scene.environment_frames() > 1,
        }))
    }
}

/// One env render's tables and per-pixel counts.
struct EnvFrames<'a> {
    env: &'a Env,
    settings: &'a EnvSettings,
    spp: u32,
    light_only: bool,
    alpha_samples: u32,
    cube: CubeTable,
    seed: u32,
    counts: Buffer<[f32; 2]>,
    alpha: Buffer<[f32; 2]>,
    alpha_terms: Buffer<[f32; 2]>,
    latlong: EquirectTable,
    pyramid: EnvPyramid,
    sequence: bool,
}

impl MethodFrames for EnvFrames<'_> {
    fn record<'a>(
        &'a self,
        shared: &Shared<'a>,
        cmd: &mut Commands<'a>,
        frame: u32,
    ) -> GpuResult<()> {
        let (settings, gpu_scene, cube) = (self.settings, shared.scene, &self.cube);
        let strategy = settings.strategy;
        let rebuild = settings.rebuild.due(frame, self.sequence);
        if strategy.uses_cube() {
            if rebuild {
                cmd.pass("cube map", |cmd| cube.record_weights(cmd, gpu_scene))?;
                cmd.pass("cdf", |cmd| cube.record_cdf(cmd))?;
            }
            // Each frame's samples are a Halton sequence from index 0 under the frame's own
            // scrambling: every pixel uses a prefix (M_f of them), and a prefix of one sequence
            // is well spread where a strided piece of a longer one is not.
            cmd.pass("light samples", |cmd| {
                (0..cube.sets).try_for_each(|set| {
                    cube.record_samples(cmd, set, 0, pcg::hash(&[self.seed, frame, set]))
                })
            })?;
        }
        if self.latlong.is_built() && rebuild {
            cmd.pass("latlong table", |cmd| self.latlong.record(cmd, gpu_scene))?;
        }
        if self.pyramid.is_built() && rebuild {
            cmd.pass("pyramid", |cmd| self.pyramid.record(cmd, gpu_scene))?;
        }
        cmd.pass("shade", |cmd| {
            self.env.shade.record(
                cmd,
                gpu_scene,
                shared.gbuffer,
                cube,
                &self.latlong,
                &self.pyramid,
                shared.accumulation,
                &self.counts,
                &self.alpha,
                &self.alpha_terms,
                &shade::ShadeSettings {
                    strategy,
                    spp: self.spp,
                    light_only: self.light_only,
                    integer_counts: settings.integer_counts,
                    alpha_samples: self.alpha_samples,
                    shadows: settings.shadows,
                    frame,
                    seed: self.seed,
                },
            )
        })
    }

    fn finish(&self, shared: &Shared<'_>) -> GpuResult<Extras> {
        let strategy = self.settings.strategy;
        let frames = self.settings.frames.max(1);
        let mut stats = vec![];
        if !matches!(strategy, Strategy::Brdf | Strategy::Cosine) {
            // Over the pixels that see a surface, per frame: the light samples used and the
            // fraction of them above the surface (Lu Fig. 3.6's effective samples).
            let counts = self.counts.read()?;
            let lit: Vec<&[f32; 2]> = counts.iter().filter(|c| c[0] > 0.0).collect();
            let used: f64 = lit.iter().map(|c| c[0] as f64).sum();
            let effective: f64 = lit.iter().map(|c| c[1] as f64).sum();
            let per_pixel = used / (lit.len().max(1) as f64 * frames as f64);
            stats.push(("light_samples_per_pixel".into(), per_pixel));
            stats.push((
                "effective_light_fraction".into(),
                if used > 0.0 { effective / used } else { 0.0 },
            ));
        }
        let mut maps = vec![];
        if strategy == Strategy::Alpha {
            let alpha = self.alpha.read()?;
            stats.push(("alpha_samples".into(), self.alpha_samples as f64));
            stats.push(("mean_alpha".into(), mean_alpha(&alpha)));
            maps.push((
                "alpha".into(),
                alpha_map(&alpha, shared.scene.width, shared.scene.height),
            ));
        }
        Ok(Extras { stats, maps })
    }
}

/// The mean over the pixels that saw a surface of alpha (the BRDF share), each pixel's alpha
/// its mean over the frames that saw a surface there ((sum, frames) per pixel).
pub fn mean_alpha(alpha_sums: &[[f32; 2]]) -> f64 {
    let lit: Vec<f64> = alpha_sums
        .iter()
        .filter(|a| a[1] > 0.0)
        .map(|a| a[0] as f64 / a[1] as f64)
        .collect();
    lit.iter().sum::<f64>() / lit.len().max(1) as f64
}

/// The alpha map (Lu 14 Fig. 5.1, 5.6): per pixel, with alpha the mean BRDF share over the
/// frames that saw a surface there ((sum, frames) per pixel), R = (1 - alpha) / max(alpha,
/// 1 - alpha) (light samples) and G = alpha / max(alpha, 1 - alpha) (BRDF samples), so
/// yellow is the balance heuristic's half and half; black where no surface is seen.
pub fn alpha_map(alpha_sums: &[[f32; 2]], width: u32, height: u32) -> Image {
    let mut map = Image::new(width, height);
    for (pixel, sum) in map.pixels.iter_mut().zip(alpha_sums) {
        if sum[1] > 0.0 {
            let a = (sum[0] / sum[1]).clamp(0.0, 1.0);
            let m = a.max(1.0 - a);
            *pixel = [(1.0 - a) / m, a / m, 0.0];
        }
    }
    map
}
