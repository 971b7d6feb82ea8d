//! Instant radiosity (Keller 97), method `ir`: per frame, the G-buffer, direct light by the
//! reference's next-event estimation (or Keller's original with the light vertices as VPLs,
//! `--direct vpl`), a fresh set of VPLs from the quasi-random walk, and the tiled gathering of
//! every (pixel, VPL) pair. Frames accumulate with fresh subpixel positions and VPL sets.

pub mod filter;
pub mod gather;
pub mod reuse;
pub mod schedule;
pub mod walk;

use std::cell::{Cell, RefCell};
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
use crate::scene::gpu::{analytic_lights, GpuLight, LightEntry};
use crate::scene::Scene;

use filter::FilterInterleaved;
use gather::AccumulateVpls;
use reuse::{ClassBuffers, Classes, History, ReweighVpls};
use schedule::{mean_albedo, Absorption, Schedule};
use walk::{PathClass, TraceVpls, Vpl, VplBuffers};

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
    /// K: the animation frames a light path lives in a sequence; each frame walks 1/K of the
    /// paths afresh and keeps the rest, re-weighed (src/methods/ir/reuse.rs). 1: every frame
    /// walks them all.
    pub reuse: u32,
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
            reuse: 1,
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
    field_setting!(
        "reuse",
        reuse,
        Kind::Count {
            min: 1,
            max: reuse::MAX_CLASSES
        },
        Count,
        "K: in a sequence, the frames a light path lives. The paths fall into K classes (K \
         interleaved walks of vpls / K paths, rounded up); each frame walks one class afresh \
         and keeps the others from the frames before, re-weighed by multiple importance \
         sampling over where the point and spot lights were when they were walked (Laine 07's \
         incremental instant radiosity; unbiased per frame on diffuse surfaces). A still \
         render, and a sequence's first frame, walk every class. 1: no classes, every frame \
         walks every path.",
        needs: &[Need::AtMost("vpls"), Need::OneOf("interleave", &["1"])],
    ),
];

pub struct InstantRadiosity {
    walk: TraceVpls,
    reweigh: ReweighVpls,
    gather: AccumulateVpls,
    filter: FilterInterleaved,
    compensation: ClampCompensation,
    /// Left by the last render that completed (reuse.rs): taken by the next render and reused
    /// where it renders that frame's successor.
    history: RefCell<Option<History>>,
}

impl InstantRadiosity {
    /// The per-frame VPL layout this scene and these settings give (`--reuse` K > 1: K
    /// interleaved classes of paths, `Schedule::interleaved`).
    pub fn schedule(scene: &Scene, settings: &IrSettings) -> Schedule {
        Schedule::interleaved(
            settings.paths,
            mean_albedo(scene),
            settings.absorption,
            settings.reuse.clamp(1, reuse::MAX_CLASSES),
        )
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
    const ACROSS_FRAMES: AcrossFrames = AcrossFrames {
        carries: &[reuse::CARRIED],
    };

    fn across_frames(settings: &IrSettings) -> AcrossFrames {
        match settings.reuse > 1 {
            true => Self::ACROSS_FRAMES,
            false => AcrossFrames::NOTHING,
        }
    }

    fn new(ctx: &Context) -> GpuResult<Self> {
        Ok(InstantRadiosity {
            walk: TraceVpls::new(ctx)?,
            reweigh: ReweighVpls::new(ctx)?,
            gather: AccumulateVpls::new(ctx)?,
            filter: FilterInterleaved::new(ctx)?,
            compensation: ClampCompensation::new(ctx)?,
            history: RefCell::new(None),
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
        animation: &AnimationFrame<'_>,
    ) -> GpuResult<Box<dyn MethodFrames + 'a>> {
        let layout = Self::schedule(scene, settings);
        let class_count = settings.reuse.clamp(1, reuse::MAX_CLASSES);
        let lights = analytic_lights(scene).0;
        // Whatever the last render left is taken: reused only by its successor.
        let history = self.history.borrow_mut().take();
        let kept = match (history, animation.previous) {
            (Some(h), Some(p))
                if class_count > 1
                    && animation.keeps(&reuse::CARRIED)
                    && reuse::lights_moved_only(p.scene, scene)
                    && h.frame == p.frame
                    && h.content_hash == p.scene.content_hash
                    && h.base.layout == layout
                    && h.classes.seeds.len() == class_count as usize
                    && bytemuck::cast_slice::<LightEntry, u8>(&h.entries)
                        == bytemuck::cast_slice::<LightEntry, u8>(
                            &gpu_scene.light_table.entries,
                        ) =>
            {
                Some(h)
            }
            _ => None,
        };
        // The first frame's walk: one class afresh where paths are kept, else all of them.
        let first_seed = walk_seed(settings, 0);
        let (vpls, classes, fresh) = match kept {
            Some(h) => {
                let fresh = animation.frame % class_count;
                let mut classes = h.classes;
                classes.seeds[fresh as usize] = reuse::class_seed(first_seed, fresh, class_count);
                classes.lights[fresh as usize] = lights.clone();
                (h.base, classes, Some(fresh))
            }
            None => (
                VplBuffers::new(ctx, layout)?,
                Classes::walked(class_count, first_seed, &lights),
                None,
            ),
        };
        let reweighed = match fresh {
            Some(_) => Some((
                Buffer::zeroed(ctx, "Vpls", vpls.layout.slot_count.max(1) as usize)?,
                ClassBuffers::new(ctx, &classes)?,
            )),
            None => None,
        };
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
            vpls: Some(vpls),
            reweighed,
            class_count,
            fresh,
            classes: RefCell::new(classes),
            lights,
            animation_frame: animation.frame,
            content_hash: scene.content_hash,
            entries: gpu_scene.light_table.entries.clone(),
            finished: Cell::new(false),
            vpl_radiance,
            interleave,
            surface,
            light_vertices,
            clamp,
        }))
    }
}

/// The seed of frame `frame`'s walk.
fn walk_seed(settings: &IrSettings, frame: u32) -> u32 {
    pcg::hash(&[settings.seed, frame, 0x76706c73])
}

/// One ir render's buffers, recording each frame's VPL walk and gather.
struct IrFrames<'a> {
    ir: &'a InstantRadiosity,
    settings: &'a IrSettings,
    /// The walk's slots (None once handed to the history).
    vpls: Option<VplBuffers>,
    /// Where paths were kept from the frame before: the first frame's VPLs re-weighed from
    /// them, and the class data the pass reads.
    reweighed: Option<(Buffer<Vpl>, ClassBuffers)>,
    class_count: u32,
    /// The class the first frame walks where paths were kept.
    fresh: Option<u32>,
    classes: RefCell<Classes>,
    lights: Vec<GpuLight>,
    animation_frame: u32,
    content_hash: u64,
    entries: Vec<LightEntry>,
    finished: Cell<bool>,
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
        let walk_vpls = self.vpls.as_ref().expect("kept until the render ends");
        let seed = walk_seed(settings, frame);
        // The first frame after kept paths walks one class and re-weighs the rest; any other
        // walks every path (so later frames of a render are independent of the first).
        let reweigh = match (frame, self.fresh, &self.reweighed) {
            (0, Some(fresh), Some(buffers)) => Some((fresh, buffers)),
            _ => None,
        };
        let k = self.class_count;
        cmd.pass("vpl walk", |cmd| {
            // Each class is a walk of its own (its own Halton set and seed); with one class,
            // the plain walk.
            let classes = match reweigh {
                Some((fresh, _)) => fresh..fresh + 1,
                None if k > 1 => 0..k,
                None => return ir.walk.record(cmd, gpu_scene, walk_vpls, seed, None),
            };
            for class in classes {
                let path_class = PathClass {
                    stride: k,
                    phase: class,
                };
                let class_seed = reuse::class_seed(seed, class, k);
                ir.walk
                    .record_paths(cmd, gpu_scene, walk_vpls, class_seed, None, path_class)?;
            }
            Ok(())
        })?;
        let vpls = match reweigh {
            Some((fresh, (frame_vpls, class_buffers))) => {
                cmd.pass("vpl reweighing", |cmd| {
                    ir.reweigh
                        .record(cmd, gpu_scene, walk_vpls, frame_vpls, class_buffers, fresh)
                })?;
                frame_vpls
            }
            None => {
                if frame > 0 {
                    *self.classes.borrow_mut() =
                        Classes::walked(self.class_count, seed, &self.lights);
                }
                &walk_vpls.vpls
            }
        };
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
                    vpls,
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
                vpls,
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
        self.finished.set(true);
        let mut stats = self.clamp.stats(shared.scene)?;
        if self.class_count > 1 {
            // The share of the first frame's light paths kept from earlier frames.
            let kept = match self.fresh {
                Some(_) => (self.class_count - 1) as f64 / self.class_count as f64,
                None => 0.0,
            };
            stats.push(("reuse_kept_paths".into(), kept));
        }
        Ok(Extras {
            stats,
            maps: vec![],
        })
    }
}

impl Drop for IrFrames<'_> {
    /// A completed render's paths become the history the next animation frame may keep.
    fn drop(&mut self) {
        if !self.finished.get() || self.class_count <= 1 {
            return;
        }
        if let Some(base) = self.vpls.take() {
            *self.ir.history.borrow_mut() = Some(History {
                frame: self.animation_frame,
                content_hash: self.content_hash,
                base,
                classes: self.classes.borrow().clone(),
                entries: std::mem::take(&mut self.entries),
            });
        }
    }
}
