//! Instant radiosity (Keller 97), method `ir`: per frame, the G-buffer, direct light by the
//! reference's next-event estimation (or Keller's original with the light vertices as VPLs,
//! `--direct vpl`), a fresh set of VPLs from the quasi-random walk, and the tiled gathering of
//! every (pixel, VPL) pair. Frames accumulate with fresh subpixel positions and VPL sets.

pub mod filter;
pub mod gather;
pub mod schedule;
pub mod walk;

use std::mem::size_of;

use crate::gpu::{Buffer, Commands, Context, GpuResult};
use crate::methods::across_frames::{AcrossFrames, AnimationFrame};
use crate::methods::compensation::{ClampCompensation, ClampSettings, FrameClamp, VplSource};
use crate::methods::device_fit;
use crate::methods::direct::{DirectLightOptions, DirectLightPaths};
use crate::methods::driver::{Extras, MethodFrames, Shared};
use crate::methods::gbuffer::PixelSampling;
use crate::methods::interface::{Lights, RenderMethod, SharedPasses, Support};
use crate::methods::lights::NO_LUMINAIRES;
use crate::methods::settings::{
    common_settings, field_setting, named_choices, Kind, Need, Setting, Value,
};
use crate::sampling::pcg;
use crate::scene::gpu::GpuScene;
use crate::scene::Scene;

use filter::FilterInterleaved;
use gather::AccumulateVpls;
use schedule::{mean_albedo, Absorption, Schedule};
use walk::{TraceVpls, Vpl, VplBuffers};

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DirectLight {
    /// The reference's next-event estimation (MIS with BSDF sampling); VPLs carry indirect
    /// light only.
    NextEvent,
    /// Keller's original: each path's light vertex is a VPL too.
    Vpl,
}

named_choices!(DirectLight {
    NextEvent => "nee",
    Vpl => "vpl",
});

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct IrSettings {
    /// N: paths started on the lights per frame.
    pub paths: u32,
    pub frames: u32,
    pub seed: u32,
    pub absorption: Absorption,
    /// The geometry-term clamp b and its bias compensation (default: b from the scene,
    /// compensated, so unbiased; src/methods/compensation.rs).
    pub clamp: ClampSettings,
    pub interleave: u32,
    pub direct: DirectLight,
    /// Direct-light samples per pixel and frame, each from its own camera ray (new subpixel
    /// position), so direct light and the pixel footprint get this many samples while the
    /// expensive indirect estimate gets one position per frame (`--direct-spp`).
    pub direct_spp: u32,
    pub pixels: PixelSampling,
}

impl Default for IrSettings {
    fn default() -> Self {
        IrSettings {
            paths: 256,
            frames: 16,
            seed: 0,
            absorption: Absorption::Fractional,
            clamp: ClampSettings::default(),
            interleave: 1,
            direct: DirectLight::NextEvent,
            // Measured (Cornell box 128x128, defaults, 2 seeds, lavapipe): relMSE 1.28e-3,
            // 9.15e-4, 7.63e-4, 6.61e-4, 5.89e-4 at 1, 2, 4, 8, 64 direct samples, which
            // e(K) = 5.78e-4 + 7.05e-4 / K fits; a direct sample costs 27 ms a frame against
            // the gather's and compensation's 1.52 s, so relMSE x time is least near
            // K = sqrt(7.05 x 1524 / (5.78 x 27)) = 8.3. At 8 direct light and the pixel
            // footprint are 13% of the error (at 1: 55%).
            direct_spp: 8,
            pixels: PixelSampling::Jittered,
        }
    }
}

/// Instant radiosity's settings (`irad methods ir`).
pub const SETTINGS: &[Setting<IrSettings>] = &[
    field_setting!(
        "vpls",
        paths,
        Kind::Count {
            min: 1,
            max: 1 << 20
        },
        Count,
        "Paths started on the lights per frame (Keller's N; about N / (1 - mean albedo) VPLs).",
    ),
    common_settings!(
        frames,
        "Frames, each with fresh VPLs and fresh subpixel positions."
    ),
    common_settings!(seed),
    Setting::new(
        "absorption",
        Kind::Choice(Absorption::NAMES),
        "fractional: floor(rho^j N) paths reach vertex j (Keller's, for stills; where that \
         reaches 0 the last paths go on by Russian roulette, so no path length is lost); \
         roulette: Russian roulette at every vertex (for animation).",
        |s| Some(Value::Name(s.absorption.name())),
        |s, v| {
            s.absorption = Absorption::from_name(v.name()).expect("a checked name");
        },
    ),
    common_settings!(clamp),
    common_settings!(compensate, needs: &[Need::Not("clamp", "0")]),
    field_setting!(
        "interleave",
        interleave,
        Kind::Count { min: 1, max: 16 },
        Count,
        "Interleaved sampling over k x k pixel blocks (1 disables it).",
    ),
    Setting::new(
        "direct",
        Kind::Choice(DirectLight::NAMES),
        "Direct light by next-event estimation (nee, as the reference) or by the light \
         vertices as VPLs (vpl, Keller's original).",
        |s| Some(Value::Name(s.direct.name())),
        |s, v| {
            s.direct = DirectLight::from_name(v.name()).expect("a checked name");
        },
    ),
    common_settings!(direct_spp),
    common_settings!(pixel_centres),
];

pub struct InstantRadiosity {
    walk: TraceVpls,
    gather: AccumulateVpls,
    filter: FilterInterleaved,
    compensation: ClampCompensation,
}

impl InstantRadiosity {
    /// The per-frame VPL layout this scene and these settings give.
    pub fn schedule(scene: &Scene, settings: &IrSettings) -> Schedule {
        Schedule::new(settings.paths, mean_albedo(scene), settings.absorption)
    }
}

impl RenderMethod for InstantRadiosity {
    type Settings = IrSettings;
    const NAME: &'static str = "ir";
    const SUMMARY: &'static str =
        "Instant radiosity (Keller 97): VPLs from a quasi-random walk from the lights.";
    const SETTINGS: &'static [Setting<IrSettings>] = SETTINGS;
    const COUNT: &'static str = "frames";
    const LIGHTS: Lights = Lights {
        environment: Support::Declines(
            "the quasi-random walk starts on emissive triangles, point and spot lights",
        ),
        area: Support::Renders,
        point: Support::Renders,
        luminaires: Support::Declines(NO_LUMINAIRES),
    };
    const ACROSS_FRAMES: AcrossFrames = AcrossFrames::NOTHING;

    fn new(ctx: &Context) -> GpuResult<Self> {
        Ok(InstantRadiosity {
            walk: TraceVpls::new(ctx)?,
            gather: AccumulateVpls::new(ctx)?,
            filter: FilterInterleaved::new(ctx)?,
            compensation: ClampCompensation::new(ctx)?,
        })
    }

    fn shared_passes(settings: &IrSettings) -> SharedPasses {
        SharedPasses {
            pixels: settings.pixels,
            direct: Some(DirectLightOptions {
                light: match settings.direct {
                    DirectLight::NextEvent => DirectLightPaths::NextEvent,
                    DirectLight::Vpl => DirectLightPaths::EmissionOnly,
                },
                reflected_environment: true,
                spp: settings.direct_spp,
            }),
        }
    }

    fn work(s: &IrSettings) -> f64 {
        s.frames as f64 * s.paths as f64
    }

    fn fits(s: &IrSettings, scene: &Scene, limit: u64) -> Result<(), String> {
        device_fit::check_compensation(&s.clamp, scene, limit)?;
        // Vpls: one slot per VPL of every path level (ir/walk.rs).
        let bytes = |paths: u64| {
            let settings = IrSettings {
                paths: paths as u32,
                ..*s
            };
            Self::schedule(scene, &settings).slot_count as u64 * size_of::<Vpl>() as u64
        };
        let paths = s.paths as u64;
        device_fit::check_size(paths, limit, bytes, |over, largest| {
            format!(
                "ir: vpls = {paths} (--vpls): the VPLs {over}; the largest that fits is {largest}"
            )
        })
    }

    /// The render's VPL buffers, the clamp and the interleave's radiance.
    fn set_up<'a>(
        &'a self,
        ctx: &Context,
        scene: &Scene,
        gpu_scene: &GpuScene,
        settings: &'a IrSettings,
        _animation: &AnimationFrame<'_>,
    ) -> GpuResult<Box<dyn MethodFrames + 'a>> {
        let vpls = VplBuffers::new(ctx, Self::schedule(scene, settings))?;
        let interleave = settings.interleave.max(1);
        let vpl_radiance = Buffer::zeroed(
            ctx,
            "VplRadiance",
            if interleave > 1 {
                gpu_scene.pixel_count()
            } else {
                1
            },
        )?;
        // The clamp and its compensation act on the surface VPLs; under `--direct vpl` the
        // light vertices are gathered unclamped (a path from x cannot hit a point light, so
        // their clamp could not be compensated).
        let surface = vpls.layout.surface_slots();
        let light_vertices = match settings.direct {
            DirectLight::NextEvent => 0..0,
            DirectLight::Vpl => 0..surface.start,
        };
        let clamp = settings
            .clamp
            .prepare(ctx, scene, gpu_scene, surface.end - surface.start)?;
        Ok(Box::new(IrFrames {
            ir: self,
            settings,
            vpls,
            vpl_radiance,
            interleave,
            surface,
            light_vertices,
            clamp,
        }))
    }
}

/// One ir render's buffers, recording each frame's VPL walk and gather.
struct IrFrames<'a> {
    ir: &'a InstantRadiosity,
    settings: &'a IrSettings,
    vpls: VplBuffers,
    vpl_radiance: Buffer<glam::Vec4>,
    interleave: u32,
    surface: std::ops::Range<u32>,
    light_vertices: std::ops::Range<u32>,
    clamp: FrameClamp,
}

impl MethodFrames for IrFrames<'_> {
    fn record<'a>(
        &'a self,
        shared: &Shared<'a>,
        cmd: &mut Commands<'a>,
        frame: u32,
    ) -> GpuResult<()> {
        let (ir, settings, gpu_scene) = (self.ir, self.settings, shared.scene);
        let walk_seed = pcg::hash(&[settings.seed, frame, 0x76706c73]);
        cmd.pass("vpl walk", |cmd| {
            ir.walk.record(cmd, gpu_scene, &self.vpls, walk_seed, None)
        })?;
        cmd.pass("vpl accumulation", |cmd| {
            if self.interleave > 1 {
                cmd.fill_zero(&self.vpl_radiance);
            }
            for (slots, clamp) in [
                (self.light_vertices.clone(), 0.0),
                (self.surface.clone(), self.clamp.g_clamp),
            ] {
                if slots.is_empty() {
                    continue;
                }
                ir.gather.record(
                    cmd,
                    gpu_scene,
                    shared.gbuffer,
                    &self.vpls.vpls,
                    shared.accumulation,
                    &self.vpl_radiance,
                    slots,
                    clamp,
                    self.interleave,
                    1.0,
                )?;
            }
            Ok(())
        })?;
        self.clamp.record_compensation(
            &ir.compensation,
            cmd,
            gpu_scene,
            shared.gbuffer,
            shared.accumulation,
            &[VplSource {
                vpls: &self.vpls.vpls,
                slots: self.surface.clone(),
                weight: 1.0,
            }],
            1.0,
            frame,
            pcg::hash(&[settings.seed, frame, 0x636f6d70]),
        )?;
        if self.interleave > 1 {
            cmd.pass("interleave filter", |cmd| {
                ir.filter.record(
                    cmd,
                    gpu_scene,
                    shared.gbuffer,
                    &self.vpl_radiance,
                    shared.accumulation,
                    self.interleave,
                )
            })?;
        }
        Ok(())
    }

    fn finish(&self, shared: &Shared<'_>) -> GpuResult<Extras> {
        Ok(Extras {
            stats: self.clamp.stats(shared.scene)?,
            maps: vec![],
        })
    }
}
