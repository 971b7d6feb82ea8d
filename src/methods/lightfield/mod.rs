//! Light-field luminaires (Lu 14 Chapter 4), method `lightfield`: per frame the
//! G-buffer and the direct light of the scene's other lights (the reference's direct-light
//! pass), then per placed luminaire Lu's two steps (Section 4.5.1):
//! glsl/lightfield/estimate_luminaire_areas.comp (A(p), pass "A estimation") and
//! glsl/lightfield/shade_lightfield.comp (K_m, the samples and their shading with a shadow ray each, by
//! the chosen strategy; pass "shade"). The luminaires' sampling tables are built on the GPU
//! at the render's start, and every frame for a luminaire whose atlases change (tables.rs).
//! src/sampling/luminaire.rs is the f64 mirror.

pub mod tables;

use bytemuck::{Pod, Zeroable};
use glam::Vec4;
use serde_json::json;

use crate::gpu::{bind, Buffer, Commands, Context, GpuError, GpuResult, Kernel};
use crate::image::Image;
use crate::methods::across_frames::{AcrossFrames, AnimationFrame};
use crate::methods::direct::{DirectLightOptions, DirectLightPaths};
use crate::methods::driver::{Extras, MethodFrames, Shared};
use crate::methods::gbuffer::PixelSampling;
use crate::methods::interface::{Lights, RenderMethod, SharedPasses, Support};
use crate::methods::rebuild::TableRebuild;
use crate::methods::settings::{
    common_settings, field_setting, named_choices, Kind, Need, Setting, Value,
};
use crate::sampling::pcg;
use crate::scene::gpu::GpuScene;
use crate::scene::luminaire::{Basis, PlacedLuminaire};
use crate::scene::Scene;

use tables::LuminaireTables;

/// How each image's samples are placed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Strategy {
    /// Lu's: restricted windows, A_m from the summed-area table, K_m by A_m (Eq. 4.11-4.17).
    Restricted,
    /// Uniform over the restricted window (Fig. 4.14's baseline).
    Uniform,
    /// One CDF over the whole image, no restriction (Fig. 4.13's baseline).
    Precomputed,
    /// Uniform over the whole image plane, K / M per image: the brute-force reference.
    BruteForce,
}

// In the order of glsl/include/luminaire.glsl's STRATEGY_* codes (`code`).
named_choices!(Strategy {
    Restricted => "restricted",
    Uniform => "uniform",
    Precomputed => "precomputed",
    BruteForce => "brute-force",
});

impl Strategy {
    /// The strategy codes of glsl/include/luminaire.glsl: the declaration order (a unit test
    /// checks the GLSL's defines).
    fn code(self) -> u32 {
        self as u32
    }
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LightfieldSettings {
    /// K: samples per pixel, luminaire and frame, spread over the images (Eq. 4.16).
    pub spp: u32,
    pub frames: u32,
    /// K_max: most samples per image.
    pub k_max: u32,
    pub strategy: Strategy,
    /// Lu's modified secant search (true) or binary search.
    pub secant: bool,
    /// Halton prefixes shared by every pixel (Section 4.5.3) instead of a rotation of them per
    /// pixel.
    pub shared_samples: bool,
    /// One shadow ray per image toward its median point instead of one per sample (Section
    /// 4.5.2's approximation: biased at shadow edges).
    pub averaged_visibility: bool,
    /// Shadow rays (false: no visibility at all, as in timings without shadows).
    pub shadows: bool,
    /// Draw the samples and shade nothing (the image stays black): `irad bench lightfield`'s
    /// measure of sampling alone.
    pub sampling_only: bool,
    /// The luminaire tables: once for a still atlas, per frame for a sequence (default), or
    /// every frame.
    pub rebuild: TableRebuild,
    pub seed: u32,
    pub pixels: PixelSampling,
}

impl Default for LightfieldSettings {
    fn default() -> Self {
        LightfieldSettings {
            spp: 200,
            frames: 4,
            k_max: 64,
            strategy: Strategy::Restricted,
            secant: true,
            shared_samples: false,
            averaged_visibility: false,
            shadows: true,
            sampling_only: false,
            rebuild: TableRebuild::WhenChanged,
            seed: 0,
            pixels: PixelSampling::Jittered,
        }
    }
}

/// Light-field luminaires' settings (`irad methods lightfield`).
pub const SETTINGS: &[Setting<LightfieldSettings>] = &[
    field_setting!(
        "spp",
        spp,
        Kind::Count {
            min: 1,
            max: 1 << 16
        },
        Count,
        "K: samples per pixel, luminaire and frame, spread over the images (Lu Eq. 4.16).",
    ),
    common_settings!(
        frames,
        "Frames, each with fresh samples and subpixel positions."
    ),
    field_setting!(
        "k_max",
        k_max,
        Kind::Count {
            min: 1,
            max: 1 << 16
        },
        Count,
        "K_max: the most samples per pixel, frame and image (Lu's Fig. 4.11).",
        // The brute force takes K / M from each image.
        needs: &[Need::OneOf(
            "strategy",
            &["restricted", "uniform", "precomputed"],
        )],
    ),
    common_settings!(seed),
    Setting::new(
        "strategy",
        Kind::Choice(Strategy::NAMES),
        "How each image's samples are placed: restricted (Lu's windows, A_m from the \
         summed-area table, K_m by A_m), uniform (uniform over the restricted window), \
         precomputed (one CDF over each whole image), brute-force (uniform over the whole \
         image plane: the reference).",
        |s| Some(Value::Name(s.strategy.name())),
        |s, v| {
            s.strategy = Strategy::from_name(v.name()).expect("a checked name");
        },
    ),
    Setting::<LightfieldSettings>::new(
        "search",
        Kind::Choice(&["binary", "secant"]),
        "How the CDFs are inverted: Lu's modified secant search, or binary search.",
        |s| Some(Value::Name(if s.secant { "secant" } else { "binary" })),
        |s, v| s.secant = v.name() == "secant",
    )
    // The strategies that invert a CDF.
    .needs(&[Need::OneOf("strategy", &["restricted", "precomputed"])]),
    field_setting!(
        "shared_samples",
        shared_samples,
        Kind::Switch,
        Switch,
        "Every pixel takes the same Halton prefixes (Lu Section 4.5.3) instead of its own \
         rotation of them (biased per pixel pattern, not in the mean).",
    ),
    field_setting!(
        "averaged_visibility",
        averaged_visibility,
        Kind::Switch,
        Switch,
        "One shadow ray per image toward its median point instead of one per sample (Lu \
         Section 4.5.2's approximation; biased at shadow edges).",
        needs: &[Need::OneOf("shadows", &["true"])],
    ),
    common_settings!(shadows),
    common_settings!(rebuild_tables),
    common_settings!(pixel_centres),
];

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct LuminaireFrame {
    position: Vec4,
    x: Vec4,
    y: Vec4,
    z: Vec4,
    plane: Vec4,
    image_size: Vec4,
    grid: [u32; 4],
    options: [u32; 4],
}

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct ShadeParams {
    frame: u32,
    seed: u32,
    search: u32,
    shared_samples: u32,
    visibility: u32,
    sampling_only: u32,
    sample_begin: u32,
    sample_end: u32,
}

/// The GLSL layouts the structs above mirror (src/gpu/contracts.rs checks them).
#[cfg(test)]
pub(crate) const GPU_LAYOUTS: &[crate::gpu::contracts::GpuLayout] = {
    use crate::gpu::contracts::gpu_layout;
    &[
        gpu_layout!(LuminaireFrame as "LuminaireFrame" {
            position,
            x,
            y,
            z,
            plane,
            image_size,
            grid,
            options,
        }),
        gpu_layout!(ShadeParams in ["shade_lightfield"] {
            frame,
            seed,
            search,
            shared_samples,
            visibility,
            sampling_only,
            sample_begin,
            sample_end,
        }),
    ]
};

/// Most samples one invocation of shade_lightfield.comp draws in one dispatch. lavapipe's
/// LLVM back end (gallivm) breaks out of every loop of an invocation once they have run
/// 65535 iterations together (LP_MAX_TGSI_LOOP_ITERATIONS, shared by every loop), silently:
/// 2240 samples per pixel in one dispatch came out at half the light. A sample loops about
/// 10 times plus its shadow ray's BVH traversal, so 256 leave room for traversals of ~200
/// steps; on a real GPU the split costs a few dispatches and keeps each one short.
pub const SAMPLES_PER_DISPATCH: u32 = 256;

/// The dispatches of one luminaire's shading: ranges of each pixel's samples (numbered image
/// after image) covering at most `most` samples, each at most SAMPLES_PER_DISPATCH long.
fn shade_parts(most: u32) -> Vec<[u32; 2]> {
    (0..most.max(1))
        .step_by(SAMPLES_PER_DISPATCH as usize)
        .map(|k| [k, k + SAMPLES_PER_DISPATCH])
        .collect()
}

/// One placed luminaire on the GPU: its tables and its frame.
struct GpuLuminaire {
    tables: LuminaireTables,
    frame: Buffer<LuminaireFrame>,
    /// The luminaire's own seed, so that two luminaires draw independent numbers.
    seed: u32,
    /// The most samples a point takes from the luminaire: each image's K_m is at most
    /// max(1, K A_m / A + 1/2) and K_max, so their sum is at most K + M and M K_max; the brute
    /// force takes max(1, K / M) from each.
    most_samples: u32,
}

impl GpuLuminaire {
    fn new(
        ctx: &Context,
        placed: &PlacedLuminaire,
        index: u32,
        settings: &LightfieldSettings,
    ) -> Result<Self, GpuError> {
        let g = &placed.luminaire.geometry;
        let texels_per_m2 =
            (g.resolution[0] * g.resolution[1]) as f64 / (g.image_size[0] * g.image_size[1]);
        let frame = LuminaireFrame {
            position: placed.position.extend(1.0),
            x: placed.x.extend(0.0),
            y: placed.y.extend(0.0),
            z: placed.z.extend(0.0),
            plane: Vec4::new(
                g.pitch[0] as f32,
                g.pitch[1] as f32,
                g.delta as f32,
                g.basis.reach() as f32,
            ),
            image_size: Vec4::new(
                g.image_size[0] as f32,
                g.image_size[1] as f32,
                texels_per_m2 as f32,
                0.0,
            ),
            grid: [
                g.grid[0] as u32,
                g.grid[1] as u32,
                g.resolution[0] as u32,
                g.resolution[1] as u32,
            ],
            options: [
                (g.basis == Basis::QuadraticBSpline) as u32,
                settings.strategy.code(),
                settings.spp.max(1),
                settings.k_max.max(1),
            ],
        };
        let images = g.images() as u32;
        let (k, k_max) = (settings.spp.max(1), settings.k_max.max(1));
        Ok(GpuLuminaire {
            tables: LuminaireTables::new(ctx, &placed.luminaire)?,
            frame: Buffer::from_slice(ctx, "LuminaireParams", &[frame])?,
            seed: pcg::hash(&[settings.seed, 0x6c66, index]),
            most_samples: match settings.strategy {
                Strategy::BruteForce => images.saturating_mul((k / images).max(1)),
                // (With slack for A(p) and the shares rounding apart in f32.)
                _ => k
                    .saturating_add(images + k / 64 + 1)
                    .min(images.saturating_mul(k_max)),
            },
        })
    }
}

pub struct Lightfield {
    estimate: Kernel,
    shade: Kernel,
}

impl RenderMethod for Lightfield {
    type Settings = LightfieldSettings;
    const NAME: &'static str = "lightfield";
    const SUMMARY: &'static str =
        "Light-field luminaires' direct light by restricted-CDF sampling (Lu 14 ch. 4).";
    const SETTINGS: &'static [Setting<LightfieldSettings>] = SETTINGS;
    const COUNT: &'static str = "frames";
    const LIGHTS: Lights = Lights {
        environment: Support::Renders,
        area: Support::Renders,
        point: Support::Renders,
        luminaires: Support::Needs("it renders light-field luminaires' direct light"),
    };
    const ACROSS_FRAMES: AcrossFrames = AcrossFrames::NOTHING;

    fn new(ctx: &Context) -> GpuResult<Self> {
        Ok(Lightfield {
            estimate: Kernel::new(ctx, "estimate_luminaire_areas")?,
            shade: Kernel::new(ctx, "shade_lightfield")?,
        })
    }

    /// The G-buffer, the emission seen and the other lights' direct light.
    fn shared_passes(settings: &LightfieldSettings) -> SharedPasses {
        SharedPasses {
            pixels: settings.pixels,
            direct: Some(DirectLightOptions {
                light: DirectLightPaths::NextEvent,
                reflected_environment: true,
                spp: 0,
            }),
        }
    }

    fn work(s: &LightfieldSettings) -> f64 {
        s.frames as f64 * s.spp as f64
    }

    /// `irad bench lightfield`'s sampling-only renders are not a setting (so not fed back),
    /// but a record must say its image is black.
    fn record_notes(s: &LightfieldSettings) -> Vec<(&'static str, serde_json::Value)> {
        match s.sampling_only {
            true => vec![("sampling_only", json!(true))],
            false => Vec::new(),
        }
    }

    fn set_up<'a>(
        &'a self,
        ctx: &Context,
        scene: &Scene,
        gpu_scene: &GpuScene,
        settings: &'a LightfieldSettings,
        _animation: &AnimationFrame<'_>,
    ) -> GpuResult<Box<dyn MethodFrames + 'a>> {
        let luminaires = scene
            .luminaires
            .iter()
            .enumerate()
            .map(|(k, l)| GpuLuminaire::new(ctx, l, k as u32, settings))
            .collect::<Result<Vec<_>, _>>()?;
        Ok(Box::new(LightfieldFrames {
            lightfield: self,
            settings,
            luminaires,
            counts: Buffer::zeroed(ctx, "LuminaireSampleCounts", gpu_scene.pixel_count())?,
            areas: Buffer::zeroed(ctx, "LuminaireAreas", gpu_scene.pixel_count())?,
            visibility: match (settings.shadows, settings.averaged_visibility) {
                (false, _) => 0,
                (true, false) => 1,
                (true, true) => 2,
            },
            frames: settings.frames.max(1),
        }))
    }
}

/// One lightfield render's luminaires and per-pixel sample counts.
struct LightfieldFrames<'a> {
    lightfield: &'a Lightfield,
    settings: &'a LightfieldSettings,
    luminaires: Vec<GpuLuminaire>,
    counts: Buffer<f32>,
    areas: Buffer<f32>,
    visibility: u32,
    frames: u32,
}

impl MethodFrames for LightfieldFrames<'_> {
    fn record_first<'a>(&'a self, cmd: &mut Commands<'a>, frame: u32) -> GpuResult<()> {
        for l in &self.luminaires {
            l.tables.record_frame(cmd, frame, self.settings.rebuild)?;
        }
        Ok(())
    }

    fn record<'a>(
        &'a self,
        shared: &Shared<'a>,
        cmd: &mut Commands<'a>,
        frame: u32,
    ) -> GpuResult<()> {
        let (lf, settings, gpu_scene) = (self.lightfield, self.settings, shared.scene);
        for l in &self.luminaires {
            let tables = [
                bind("LuminaireTexels", &l.tables.texels),
                bind("ColumnCdf", &l.tables.column_cdf),
                bind("LuminaireSat", &l.tables.sat),
                bind("LuminaireParams", &l.frame),
                bind("LuminaireAreas", &self.areas),
            ];
            cmd.pass("A estimation", |cmd| {
                let mut bindings = gpu_scene.scene_bindings();
                bindings.push(bind("GBuffer", &shared.gbuffer.texels));
                bindings.extend(tables.iter().map(|b| bind(b.name, b.buffer)));
                lf.estimate
                    .dispatch(cmd, &bindings, &(), gpu_scene.image_workgroups())
            })?;
            cmd.pass("shade", |cmd| {
                let mut bindings = gpu_scene.bindings();
                bindings.push(bind("GBuffer", &shared.gbuffer.texels));
                bindings.extend(shared.accumulation.bindings());
                bindings.extend(tables.iter().map(|b| bind(b.name, b.buffer)));
                bindings.push(bind("LuminaireSampleCounts", &self.counts));
                for [sample_begin, sample_end] in shade_parts(l.most_samples) {
                    let params = ShadeParams {
                        frame,
                        seed: l.seed,
                        search: settings.secant as u32,
                        shared_samples: settings.shared_samples as u32,
                        visibility: self.visibility,
                        sampling_only: settings.sampling_only as u32,
                        sample_begin,
                        sample_end,
                    };
                    lf.shade
                        .dispatch(cmd, &bindings, &params, gpu_scene.image_workgroups())?;
                }
                Ok(())
            })?;
        }
        Ok(())
    }

    fn finish(&self, shared: &Shared<'_>) -> GpuResult<Extras> {
        let frames = self.frames;
        let counts = self.counts.read()?;
        let lit = counts.iter().filter(|&&c| c > 0.0).count();
        let drawn: f64 = counts.iter().map(|&c| c as f64).sum();
        let most = counts.iter().fold(0.0f32, |a, &c| a.max(c));
        let mut map = Image::new(shared.scene.width, shared.scene.height);
        for (texel, &c) in map.pixels.iter_mut().zip(&counts) {
            *texel = [c / most.max(1.0); 3];
        }
        Ok(Extras {
            stats: vec![
                (
                    "luminaire_samples_per_pixel".into(),
                    drawn / (lit.max(1) as f64 * frames as f64),
                ),
                ("pixels_with_luminaire_samples".into(), lit as f64),
                (
                    "most_luminaire_samples_per_pixel".into(),
                    most as f64 / frames as f64,
                ),
            ],
            // Where the samples went: each pixel's samples over the most any pixel took.
            maps: vec![("samples".into(), map)],
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The parts cover every sample number below `most` exactly once.
    #[test]
    fn shade_parts_cover_every_sample_once() {
        for most in [1, 7, 255, 256, 257, 600, 6435] {
            let mut seen = vec![0u32; most as usize];
            for [k0, k1] in shade_parts(most) {
                assert!(k1 - k0 <= SAMPLES_PER_DISPATCH);
                for k in k0..k1.min(most) {
                    seen[k as usize] += 1;
                }
            }
            assert!(seen.iter().all(|&c| c == 1), "most {most}");
        }
    }
}
