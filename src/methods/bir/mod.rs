//! Bidirectional instant radiosity (Segovia 06), method `bir`: VPLs from the lights (standard,
//! Keller's walk as in `ir`) and from the camera (reverse: the ends of length-2 camera paths,
//! Section 3.1), per frame. Direct light is the reference's next-event estimation; the VPLs
//! carry indirect light. `--strategy standard` shades standard VPLs only (ir's estimator),
//! `reverse` reverse VPLs only (standard VPLs then only light the reverse ones), `both` each
//! side at weight 1/2: two unbiased estimators of the same indirect light, averaged.
//!
//! Budget: `vpls` VPLs per frame. The standard side gets the light paths whose fractional
//! absorption schedule yields about its share of surface VPLs (Keller: N rho / (1 - rho)); the
//! reverse side its share of reverse VPLs. `standard` gives its whole budget to the standard
//! side; `reverse` to the reverse side, plus half a budget of light paths that light them;
//! `both` half to each.

pub mod light_cdf;
pub mod resample;
pub mod reverse;

use std::mem::size_of;

use crate::gpu::{Buffer, Commands, Context, GpuError, GpuResult};
use crate::methods::accumulation::Accumulation;
use crate::methods::across_frames::{AcrossFrames, AnimationFrame};
use crate::methods::compensation::{ClampCompensation, ClampSettings, FrameClamp, VplSource};
use crate::methods::device_fit;
use crate::methods::direct::{DirectLightOptions, DirectLightPaths};
use crate::methods::driver::{Extras, MethodFrames, Shared};
use crate::methods::gbuffer::{GBuffer, PixelSampling};
use crate::methods::interface::{Lights, RenderMethod, SharedPasses, Support};
use crate::methods::ir::gather::AccumulateVpls;
use crate::methods::ir::schedule::{mean_albedo, Absorption, Schedule};
use crate::methods::ir::walk::{TraceVpls, Vpl, VplBuffers};
use crate::methods::lights::NO_LUMINAIRES;
use crate::methods::settings::{
    common_settings, field_setting, named_choices, Kind, Need, Setting, Value,
};
use crate::sampling::pcg;
use crate::scene::gpu::GpuScene;
use crate::scene::Scene;

use light_cdf::LightCdf;
use resample::{Candidates, EstimateVplPower, ResampleBuffers, ResampleVpls, UpdateSideWeights};
use reverse::{FindUncoveredVpls, ShadeReverseVpls, StandardSet, TraceReverseVpls};

/// Which VPLs a frame shades.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Strategy {
    Standard,
    Reverse,
    Both,
}

named_choices!(Strategy {
    Standard => "standard",
    Reverse => "reverse",
    Both => "both",
});

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BirSettings {
    /// VPLs per frame (standard and reverse together).
    pub vpls: u32,
    pub frames: u32,
    pub seed: u32,
    pub strategy: Strategy,
    /// Camera points per frame the reverse VPLs start from (Eq. 7's M).
    pub pool: u32,
    /// Next-event samples per reverse VPL for its radiance (and bounces to x3).
    pub light_samples: u32,
    /// Standard VPLs each x3 connects to (drawn uniformly, weighted; 0: all of them, the
    /// default: in the Cornell box 16 drawn connections raised relMSE about 9x, as a nearby
    /// VPL drawn with weight slots / 16 is a spike).
    pub connections: u32,
    /// Vertices the paths from a reverse VPL go on for before they connect to the standard
    /// VPLs (next-event estimation at each).
    pub depth: u32,
    /// Candidates per kept VPL (the paper's r); 0 shades every candidate (no resampling).
    pub ratio: u32,
    /// The CDF's uniform floor, as a fraction of the mean candidate power (Fig. 3). The
    /// default 1 makes the CDF half uniform over the non-empty candidates (a defensive
    /// mixture): no drawn VPL weighs more than twice the mean. In the cells test scene
    /// (tests/bir.rs) 0.1 kept the mean at a standard error of 4.8%, 0.5 at 1.2%, 1 at 0.9%.
    pub floor: f32,
    /// Camera points per candidate for its power estimate (the paper's fast M = 5).
    pub power_samples: u32,
    /// Candidates resampled together: the frame's `vpls` in batches of this many, so storage
    /// stays O(batch + N') (end of Section 4.2). 0: one batch per frame.
    pub batch: u32,
    /// Start light paths by each light's measured contribution to the camera (Section 4.1)
    /// instead of by its power.
    pub light_cdf: bool,
    /// `both` with resampling: the standard side's weight follows the fraction of earlier
    /// batches in which it brought more camera power than the reverse side, sharpened
    /// (update_side_weights.comp), so a side whose batches usually bring less (a starving one)
    /// weighs almost nothing, instead of the paper's fixed 1/2.
    pub adaptive: bool,
    /// The gather's geometry-term clamp and its bias compensation (default: b from the scene
    /// and the kept VPL count, compensated; src/methods/compensation.rs).
    pub clamp: ClampSettings,
    /// Direct-light samples per pixel and frame, each from its own camera ray (new subpixel
    /// position), so direct light and the pixel footprint get this many samples while the
    /// expensive indirect estimate gets one position per frame (`--direct-spp`).
    pub direct_spp: u32,
    pub pixels: PixelSampling,
    /// H: the reverse VPLs' radiance connects to the standard VPLs of this batch and the H - 1
    /// batches before it in the render, each set weighted 1 / H (1: this batch's alone).
    pub reverse_history: u32,
}

impl Default for BirSettings {
    fn default() -> Self {
        BirSettings {
            vpls: 256,
            frames: 16,
            seed: 0,
            strategy: Strategy::Both,
            pool: 50,
            light_samples: 4,
            connections: 0,
            depth: 3,
            ratio: 10,
            floor: 1.0,
            power_samples: 5,
            batch: 0,
            light_cdf: true,
            adaptive: true,
            clamp: ClampSettings::default(),
            // Measured (Cornell box 128x128, defaults, 2 seeds, lavapipe): relMSE 2.11e-3 at 1
            // direct sample and 1.45e-3 at 32, so e(K) = 1.42e-3 + 6.9e-4 / K; a direct sample
            // costs 26.5 ms a frame against the rest's 423 ms, so relMSE x time is least near
            // K = 2.8 and within 2% of it from 2 to 4. At 4 direct light and the pixel
            // footprint are 11% of the error (at 1: 33%).
            direct_spp: 4,
            pixels: PixelSampling::Jittered,
            reverse_history: 1,
        }
    }
}

/// The strategies with reverse VPLs, where their settings apply.
const REVERSE: &[&str] = &["reverse", "both"];

/// Bidirectional instant radiosity's settings (`irad methods bir`).
pub const SETTINGS: &[Setting<BirSettings>] = &[
    field_setting!(
        "vpls",
        vpls,
        Kind::Count {
            min: 2,
            max: 1 << 20
        },
        Count,
        "VPLs per frame, standard and reverse together (the candidates, with resampling).",
    ),
    common_settings!(
        frames,
        "Frames, each with fresh VPLs and fresh subpixel positions."
    ),
    common_settings!(seed),
    Setting::new(
        "strategy",
        Kind::Choice(Strategy::NAMES),
        "Which VPLs are shaded: standard (from the lights), reverse (ends of length-2 camera \
         paths) or both, resampled together.",
        |s| Some(Value::Name(s.strategy.name())),
        |s, v| {
            s.strategy = Strategy::from_name(v.name()).expect("a checked name");
        },
    ),
    field_setting!(
        "pool",
        pool,
        Kind::Count {
            min: 1,
            max: 1 << 16
        },
        Count,
        "Camera points per frame the reverse VPLs start from (the M of Segovia's Eq. 7).",
        needs: &[Need::OneOf("strategy", REVERSE)],
    ),
    field_setting!(
        "light_samples",
        light_samples,
        Kind::Count { min: 1, max: 1024 },
        Count,
        "Next-event samples per reverse VPL for its outgoing radiance.",
        needs: &[Need::OneOf("strategy", REVERSE)],
    ),
    field_setting!(
        "connections",
        connections,
        Kind::Count {
            min: 0,
            max: 1 << 20
        },
        Count,
        "Standard VPLs each bounce from a reverse VPL connects to for its radiance (drawn \
         uniformly, weighted; 0: every one).",
        needs: &[Need::OneOf("strategy", REVERSE)],
    ),
    field_setting!(
        "depth",
        depth,
        Kind::Count { min: 1, max: 64 },
        Count,
        "Vertices the paths from a reverse VPL go on for (next-event estimation at each) \
         before they connect to the standard VPLs.",
        needs: &[Need::OneOf("strategy", REVERSE)],
    ),
    field_setting!(
        "ratio",
        ratio,
        Kind::Count {
            min: 0,
            max: 1 << 16
        },
        Count,
        "Candidates per kept VPL (the paper's resampling ratio r); 0 shades every candidate, \
         no resampling.",
    ),
    field_setting!(
        "floor",
        floor,
        Kind::Number,
        Number,
        "The resampling CDF's uniform floor, a fraction of the mean candidate power (1: half \
         the draws uniform over the candidates; 0: none, which darkens the image where powers \
         are underestimated: Segovia Fig. 3).",
        // The resampling CDF's and the light CDF's floor.
        needs: &[Need::Any(&[
            Need::Not("ratio", "0"),
            Need::OneOf("light_cdf", &["true"]),
        ])],
    ),
    field_setting!(
        "power_samples",
        power_samples,
        Kind::Count { min: 1, max: 1024 },
        Count,
        "Camera points per candidate for its power estimate.",
        needs: &[Need::Not("ratio", "0")],
    ),
    field_setting!(
        "batch",
        batch,
        Kind::Count {
            min: 0,
            max: 1 << 20
        },
        Count,
        "Candidates resampled together (0: the whole frame's), so storage stays O(batch + \
         kept VPLs).",
    ),
    field_setting!(
        "light_cdf",
        light_cdf,
        Kind::Switch,
        Switch,
        "Choose the lights that start light paths by their measured contribution to what the \
         camera sees (Segovia Section 4.1), or by their power (false).",
    ),
    field_setting!(
        "adaptive",
        adaptive,
        Kind::Switch,
        Switch,
        "With strategy both and resampling (ratio > 0): side weights that follow how often each side brought more camera \
         power in earlier batches (sharpened toward the side that usually wins), or the paper's fixed 1/2 (false).",
        // The side weights are the resampling's.
        needs: &[Need::OneOf("strategy", &["both"]), Need::Not("ratio", "0")],
    ),
    common_settings!(clamp),
    common_settings!(compensate, needs: &[Need::Not("clamp", "0")]),
    common_settings!(direct_spp),
    common_settings!(pixel_centres),
    field_setting!(
        "reverse_history",
        reverse_history,
        Kind::Count {
            min: 1,
            max: MAX_REVERSE_HISTORY
        },
        Count,
        "H: the reverse VPLs' radiance connects to the standard VPLs of this batch and of the \
         H - 1 batches before it in the render (earlier frames of a still), each set weighted \
         1 / the sets used: the same light estimated from up to H times the light paths, for \
         as many times the connections. 1: this batch's alone. Not with the adaptive side \
         weights, which earlier sets' batches set (a batch's weights would depend on the light \
         paths its reverse VPLs connect to).",
        // Above 1 also refused with the adaptive side weights (`fits`).
        needs: &[Need::OneOf("strategy", REVERSE)],
    ),
];

/// Most standard VPL sets the reverse radiance connects to.
pub const MAX_REVERSE_HISTORY: u32 = 16;

/// How a frame's budget splits.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Split {
    /// Light paths of the standard walk.
    pub light_paths: u32,
    pub reverse: u32,
    /// Weights of the standard and reverse sides in the image.
    pub standard_weight: f32,
    pub reverse_weight: f32,
}

impl Split {
    /// The split of `vpls` VPLs under `strategy`.
    pub fn new(strategy: Strategy, vpls: u32, mean_albedo: f64) -> Split {
        let n = vpls.max(2);
        // Light paths that give about `vpls` surface VPLs: N rho / (1 - rho) of them.
        let paths_for = |vpls: u32| -> u32 {
            let rho = mean_albedo.clamp(0.05, 0.95);
            ((vpls as f64 * (1.0 - rho) / rho).ceil() as u32).max(1)
        };
        match strategy {
            Strategy::Standard => Split {
                light_paths: paths_for(n),
                reverse: 0,
                standard_weight: 1.0,
                reverse_weight: 0.0,
            },
            Strategy::Reverse => Split {
                light_paths: paths_for(n / 2),
                reverse: n,
                standard_weight: 0.0,
                reverse_weight: 1.0,
            },
            Strategy::Both => Split {
                light_paths: paths_for(n / 2),
                reverse: n - n / 2,
                standard_weight: 0.5,
                reverse_weight: 0.5,
            },
        }
    }
}

pub struct Bir {
    walk: TraceVpls,
    trace_reverse: TraceReverseVpls,
    shade_reverse: ShadeReverseVpls,
    find_uncovered: FindUncoveredVpls,
    power: EstimateVplPower,
    resample: ResampleVpls,
    side_weights: UpdateSideWeights,
    gather: AccumulateVpls,
    compensation: ClampCompensation,
}

/// VPLs per frame and per batch for `vpls` and the `batch` setting (0: the whole frame).
fn batching(vpls: u32, batch: u32) -> (u32, u32) {
    let per_frame = vpls.max(2);
    match batch {
        0 => (per_frame, per_frame),
        b => (per_frame, b.clamp(2, per_frame)),
    }
}

/// The smallest weight an adaptive side weight takes: neither side is ever dropped.
pub const MIN_SIDE_WEIGHT: f32 = 0.02;

/// Below this many light entries a camera-driven table cannot differ from the power-based one.
const LIGHT_CDF_MIN_ENTRIES: usize = 2;

impl RenderMethod for Bir {
    type Settings = BirSettings;
    const NAME: &'static str = "bir";
    const SUMMARY: &'static str =
        "Bidirectional instant radiosity (Segovia 06): VPLs from the lights and from the camera.";
    const SETTINGS: &'static [Setting<BirSettings>] = SETTINGS;
    const COUNT: &'static str = "frames";
    const LIGHTS: Lights = Lights {
        environment: Support::Declines(
            "standard VPLs start on emissive triangles, point and spot lights",
        ),
        area: Support::Renders,
        point: Support::Renders,
        luminaires: Support::Declines(NO_LUMINAIRES),
    };
    const ACROSS_FRAMES: AcrossFrames = AcrossFrames::NOTHING;

    fn new(ctx: &Context) -> GpuResult<Self> {
        Ok(Bir {
            walk: TraceVpls::new(ctx)?,
            trace_reverse: TraceReverseVpls::new(ctx)?,
            shade_reverse: ShadeReverseVpls::new(ctx)?,
            find_uncovered: FindUncoveredVpls::new(ctx)?,
            power: EstimateVplPower::new(ctx)?,
            resample: ResampleVpls::new(ctx)?,
            side_weights: UpdateSideWeights::new(ctx)?,
            gather: AccumulateVpls::new(ctx)?,
            compensation: ClampCompensation::new(ctx)?,
        })
    }

    fn shared_passes(settings: &BirSettings) -> SharedPasses {
        SharedPasses {
            pixels: settings.pixels,
            direct: Some(DirectLightOptions {
                light: DirectLightPaths::NextEvent,
                reflected_environment: true,
                spp: settings.direct_spp,
            }),
        }
    }

    fn work(s: &BirSettings) -> f64 {
        s.frames as f64 * s.vpls as f64
    }

    fn fits(s: &BirSettings, scene: &Scene, limit: u64) -> Result<(), String> {
        // Earlier batches set the adaptive side weights, so with their light paths in the
        // reverse radiance a batch's weights would depend on what it connects to: a bias.
        if s.reverse_history > 1 && s.adaptive && s.strategy == Strategy::Both && s.ratio > 0 {
            return Err(format!(
                "bir: reverse_history = {} (--reverse-history) needs adaptive = false \
                 (--adaptive=false), strategy = \"reverse\" or ratio = 0: the adaptive side \
                 weights come from earlier batches, whose light paths the reverse VPLs would \
                 connect to",
                s.reverse_history
            ));
        }
        device_fit::check_compensation(&s.clamp, scene, limit)?;
        // Vpls: the standard walk's slots for a batch's light paths (set_up).
        let rho = mean_albedo(scene);
        let bytes = |vpls: u64| {
            let (_, batch) = batching(vpls as u32, s.batch);
            let split = Split::new(s.strategy, batch, rho);
            Schedule::new(split.light_paths, rho, Absorption::Fractional).slot_count as u64
                * size_of::<Vpl>() as u64
        };
        let vpls = s.vpls as u64;
        device_fit::check_size(vpls, limit, bytes, |over, largest| {
            format!(
                "bir: vpls = {vpls} (--vpls): the standard VPLs {over}; the largest that fits \
                 is {largest} (or a smaller batch)"
            )
        })
    }

    /// The render's split of VPLs into batches and sides, its VPL buffers, resampling buffers,
    /// light table and clamp.
    fn set_up<'a>(
        &'a self,
        ctx: &Context,
        scene: &Scene,
        gpu_scene: &GpuScene,
        settings: &'a BirSettings,
        _animation: &AnimationFrame<'_>,
    ) -> GpuResult<Box<dyn MethodFrames + 'a>> {
        let rho = mean_albedo(scene);
        let (vpls_per_frame, batch) = batching(settings.vpls, settings.batch);
        let batches = vpls_per_frame.div_ceil(batch);
        let split = Split::new(settings.strategy, batch, rho);
        let resampling = settings.ratio > 0;
        let draws = (batch / settings.ratio.max(1)).max(1);
        let vpls = VplBuffers::new(
            ctx,
            Schedule::new(split.light_paths, rho, Absorption::Fractional),
        )?;
        let reverse: Buffer<Vpl> =
            Buffer::zeroed(ctx, "ReverseVpls", split.reverse.max(1) as usize)?;
        let unused = Buffer::zeroed(ctx, "VplRadiance", 1)?;
        let slots = vpls.layout.surface_slots();
        let standard_count = if split.standard_weight > 0.0 {
            slots.end - slots.start
        } else {
            0
        };
        let candidates = standard_count + split.reverse;
        let resample_buffers = ResampleBuffers::new(
            ctx,
            candidates,
            [split.standard_weight, split.reverse_weight],
        )?;
        let adaptive = resampling && settings.adaptive && settings.strategy == Strategy::Both;
        let kept: Buffer<Vpl> = Buffer::zeroed(
            ctx,
            "KeptVpls",
            if resampling {
                (draws * batches) as usize
            } else {
                1
            },
        )?;
        let light_cdf =
            if settings.light_cdf && gpu_scene.light_entries.len() >= LIGHT_CDF_MIN_ENTRIES {
                Some(LightCdf::new(ctx, gpu_scene)?)
            } else {
                None
            };
        // b from the VPLs a frame shades: the kept ones, or every candidate of every batch.
        let shaded_per_frame = if resampling {
            draws * batches
        } else {
            candidates * batches
        };
        let clamp = settings
            .clamp
            .prepare(ctx, scene, gpu_scene, shaded_per_frame)?;
        // Earlier batches' standard VPL sets for the reverse radiance (none without reverse
        // VPLs).
        let history_sets = match split.reverse {
            0 => 0,
            _ => settings.reverse_history.clamp(1, MAX_REVERSE_HISTORY) as usize - 1,
        };
        let history = StandardHistory {
            sets: (0..history_sets)
                .map(|_| Buffer::zeroed(ctx, "StandardHistory", vpls.vpls.len()))
                .collect::<GpuResult<_>>()?,
        };
        Ok(Box::new(BirFrames {
            bir: self,
            settings,
            batches,
            split,
            resampling,
            draws,
            vpls,
            reverse,
            unused,
            slots,
            standard_count,
            candidates,
            resample_buffers,
            adaptive,
            kept,
            light_cdf,
            clamp,
            history,
        }))
    }
}

/// One bir render's VPLs, resampling buffers, light table and clamp.
struct BirFrames<'a> {
    bir: &'a Bir,
    settings: &'a BirSettings,
    batches: u32,
    split: Split,
    resampling: bool,
    draws: u32,
    vpls: VplBuffers,
    reverse: Buffer<Vpl>,
    unused: Buffer<glam::Vec4>,
    slots: std::ops::Range<u32>,
    standard_count: u32,
    candidates: u32,
    resample_buffers: ResampleBuffers,
    adaptive: bool,
    kept: Buffer<Vpl>,
    light_cdf: Option<LightCdf>,
    clamp: FrameClamp,
    /// The standard VPLs of the batches before (`reverse_history` - 1 sets, a ring).
    history: StandardHistory,
}

/// Earlier batches' standard VPLs, as their walk left them (before the uncovered pass marks
/// them), for the reverse radiance.
struct StandardHistory {
    sets: Vec<Buffer<Vpl>>,
}

impl MethodFrames for BirFrames<'_> {
    fn record<'a>(
        &'a self,
        shared: &Shared<'a>,
        cmd: &mut Commands<'a>,
        frame: u32,
    ) -> GpuResult<()> {
        let (bir, settings, gpu_scene) = (self.bir, self.settings, shared.scene);
        // Once per render, on the first frame's G-buffer: the table only steers which lights
        // start paths (each walk divides by the probability it used), so it need not change
        // per frame, and lavapipe pays per dispatch.
        if let (Some(cdf), 0) = (&self.light_cdf, frame) {
            let seed = pcg::hash(&[settings.seed, 0x6c636466]);
            cmd.pass("light cdf", |cmd| {
                cdf.record(cmd, gpu_scene, shared.gbuffer, seed, settings.floor)
            })?;
        }
        for b in 0..self.batches {
            self.record_batch(shared, cmd, frame, b)?;
        }
        if self.resampling {
            // Each batch's draws estimate its candidates' sum; the batches are `batches`
            // estimates of one frame's.
            let sources = [VplSource {
                vpls: &self.kept,
                slots: 0..self.draws * self.batches,
                weight: 1.0 / self.batches as f32,
            }];
            let seed = pcg::hash(&[settings.seed, frame, 0x636f6d70]);
            bir.gather_compensated(
                cmd,
                gpu_scene,
                shared.gbuffer,
                shared.accumulation,
                &self.unused,
                &self.clamp,
                &sources,
                1.0,
                frame,
                seed,
            )?;
        }
        Ok(())
    }

    fn finish(&self, shared: &Shared<'_>) -> GpuResult<Extras> {
        let settings = self.settings;
        let mut stats = self.clamp.stats(shared.scene)?;
        if self.resampling {
            let kept_counts = self.resample_buffers.stats.read()?;
            let all = (kept_counts[0] + kept_counts[1]).max(1) as f64;
            stats.push(("kept_standard_fraction".into(), kept_counts[0] as f64 / all));
            stats.push(("kept_reverse_fraction".into(), kept_counts[1] as f64 / all));
            if self.adaptive {
                let side = self.resample_buffers.side.read()?[0];
                stats.push(("final_standard_weight".into(), side[0] as f64));
            }
        }
        let sampling_rays = sampling_rays(
            &self.vpls.layout,
            &self.split,
            settings,
            self.standard_count,
            self.resampling,
        );
        let kept_per_frame = if self.resampling {
            self.draws
        } else {
            self.candidates
        } as f64;
        stats.push((
            "sampling_rays_per_kept_vpl".into(),
            sampling_rays / kept_per_frame,
        ));
        stats.push((
            "gather_rays_per_kept_vpl".into(),
            shared.scene.pixel_count() as f64,
        ));
        Ok(Extras {
            stats,
            maps: vec![],
        })
    }
}

impl<'f> BirFrames<'f> {
    /// Batch `b` of frame `frame`: its standard walk, reverse VPLs and their radiance, the
    /// pool's coverage, and either its resampling or (without) its gather.
    fn record_batch<'a>(
        &'a self,
        shared: &Shared<'a>,
        cmd: &mut Commands<'a>,
        frame: u32,
        b: u32,
    ) -> GpuResult<()> {
        let (bir, settings, gpu_scene, gbuffer) =
            (self.bir, self.settings, shared.scene, shared.gbuffer);
        let (split, slots, standard_count) = (&self.split, &self.slots, self.standard_count);
        let (vpls, reverse, resampling) = (&self.vpls, &self.reverse, self.resampling);
        let entries = self.light_cdf.as_ref().map(|c| &c.table);
        let walk_seed = pcg::hash(&[settings.seed, frame, b, 0x76706c73]);
        let reverse_seed = pcg::hash(&[settings.seed, frame, b, 0x72657672]);
        let power_seed = pcg::hash(&[settings.seed, frame, b, 0x706f7772]);
        cmd.pass("vpl walk", |cmd| {
            bir.walk.record(cmd, gpu_scene, vpls, walk_seed, entries)
        })?;
        if split.reverse > 0 {
            cmd.pass("reverse vpls", |cmd| {
                bir.trace_reverse.record(
                    cmd,
                    gpu_scene,
                    gbuffer,
                    reverse,
                    settings.pool,
                    reverse_seed,
                )
            })?;
            cmd.pass("reverse radiance", |cmd| {
                // Resampling applies the side weights itself.
                let side = if resampling {
                    1.0
                } else {
                    split.reverse_weight
                };
                // The render's batch g has min(g, H - 1) earlier sets, the ring's slot g mod
                // (H - 1) the oldest (derived from the batch, not kept: a frame may be
                // recorded without running, as irad render's progress probe does).
                let sets_held = self.history.sets.len();
                let g = (frame * self.batches + b) as usize;
                let earlier = g.min(sets_held);
                let weight = 1.0 / (1 + earlier) as f32;
                let sets = std::iter::once((&vpls.vpls, false))
                    .chain(self.history.sets[..earlier].iter().map(|s| (s, true)));
                for (set, earlier_set) in sets {
                    bir.shade_reverse.record(
                        cmd,
                        gpu_scene,
                        reverse,
                        set,
                        slots.clone(),
                        settings.light_samples,
                        settings.connections,
                        settings.depth,
                        reverse_seed,
                        side,
                        StandardSet {
                            weight,
                            history: earlier_set,
                        },
                    )?;
                }
                // This batch's set joins the history in place of the oldest.
                if sets_held > 0 {
                    cmd.copy(&vpls.vpls, &self.history.sets[g % sets_held]);
                }
                Ok(())
            })?;
            // After the radiance pass, which connects to their unscaled power.
            if standard_count > 0 {
                cmd.pass("uncovered vpls", |cmd| {
                    bir.find_uncovered.record(
                        cmd,
                        gpu_scene,
                        gbuffer,
                        &vpls.vpls,
                        slots.clone(),
                        settings.pool,
                        reverse_seed,
                        // Without resampling the gather weighs them a_s.
                        if resampling {
                            1.0
                        } else {
                            1.0 / split.standard_weight
                        },
                    )
                })?;
            }
        }
        if resampling {
            return self.record_resampling(shared, cmd, b, power_seed);
        }
        let batches = self.batches;
        let sources = unresampled_sources(vpls, reverse, split, 1.0 / batches as f32);
        let seed = pcg::hash(&[settings.seed, frame, b, 0x636f6d70]);
        bir.gather_compensated(
            cmd,
            gpu_scene,
            gbuffer,
            shared.accumulation,
            &self.unused,
            &self.clamp,
            &sources,
            // The sides' weights sum to 1: each batch is 1 / batches of the frame's estimate.
            1.0 / batches as f32,
            frame,
            seed,
        )
    }

    /// Batch `b`'s candidates' power estimates, then its draws into the kept VPLs (and the
    /// adaptive side weights' update).
    fn record_resampling<'a>(
        &'a self,
        shared: &Shared<'a>,
        cmd: &mut Commands<'a>,
        b: u32,
        power_seed: u32,
    ) -> GpuResult<()> {
        let (bir, settings, gpu_scene, gbuffer) =
            (self.bir, self.settings, shared.scene, shared.gbuffer);
        let (slots, standard_count) = (&self.slots, self.standard_count);
        let resample_buffers = &self.resample_buffers;
        cmd.pass("vpl power", |cmd| {
            bir.power.record(
                cmd,
                gpu_scene,
                gbuffer,
                &self.vpls.vpls,
                slots.start,
                standard_count,
                0,
                resample_buffers,
                settings.power_samples,
                power_seed,
                1.0,
            )?;
            bir.power.record(
                cmd,
                gpu_scene,
                gbuffer,
                &self.reverse,
                0,
                self.split.reverse,
                standard_count,
                resample_buffers,
                settings.power_samples,
                power_seed,
                1.0,
            )
        })?;
        let sources = Candidates {
            standard: &self.vpls.vpls,
            standard_begin: slots.start,
            standard_count,
            reverse: &self.reverse,
        };
        cmd.pass("resampling", |cmd| {
            bir.resample.record(
                cmd,
                &sources,
                resample_buffers,
                &self.kept,
                b * self.draws,
                self.draws,
                settings.floor,
                power_seed,
            )?;
            if self.adaptive {
                bir.side_weights
                    .record(cmd, resample_buffers, standard_count, MIN_SIDE_WEIGHT)?;
            }
            Ok(())
        })
    }
}

impl Bir {
    /// Pass "vpl accumulation" over `sources` at the clamp, then its compensation, whose
    /// next-event term weighs `direct_weight` (FrameClamp::record_compensation).
    #[allow(clippy::too_many_arguments)]
    fn gather_compensated<'a>(
        &'a self,
        cmd: &mut Commands<'a>,
        gpu_scene: &'a GpuScene,
        gbuffer: &'a GBuffer,
        accumulation: &'a Accumulation,
        unused: &'a Buffer<glam::Vec4>,
        clamp: &'a FrameClamp,
        sources: &[VplSource<'a>],
        direct_weight: f32,
        frame: u32,
        seed: u32,
    ) -> Result<(), GpuError> {
        cmd.pass("vpl accumulation", |cmd| {
            for source in sources {
                self.gather.record(
                    cmd,
                    gpu_scene,
                    gbuffer,
                    source.vpls,
                    accumulation,
                    unused,
                    source.slots.clone(),
                    clamp.g_clamp,
                    1,
                    source.weight,
                )?;
            }
            Ok(())
        })?;
        clamp.record_compensation(
            &self.compensation,
            cmd,
            gpu_scene,
            gbuffer,
            accumulation,
            sources,
            direct_weight,
            frame,
            seed,
        )
    }
}

/// Without resampling: every candidate of a batch shaded, each side at its weight (the reverse
/// side's is in its VPLs' power).
fn unresampled_sources<'a>(
    vpls: &'a VplBuffers,
    reverse: &'a Buffer<Vpl>,
    split: &Split,
    scale: f32,
) -> Vec<VplSource<'a>> {
    let mut sources = Vec::new();
    if split.standard_weight > 0.0 {
        sources.push(VplSource {
            vpls: &vpls.vpls,
            slots: vpls.layout.surface_slots(),
            weight: split.standard_weight * scale,
        });
    }
    if split.reverse > 0 {
        sources.push(VplSource {
            vpls: reverse,
            slots: 0..split.reverse,
            weight: scale,
        });
    }
    sources
}

/// Rays the sampling pass casts per batch, at most (every slot and sample assumed alive): the
/// walk's closest hits, the reverse VPLs' trace and Eq. 7 shadow rays, their radiance (next
/// events at x2 and x3, the x3 trace, one shadow ray per standard VPL), the coverage test of
/// the standard VPLs, and the power estimates' shadow rays.
fn sampling_rays(
    layout: &Schedule,
    split: &Split,
    settings: &BirSettings,
    standard_count: u32,
    resampling: bool,
) -> f64 {
    let walk = layout.slot_count as f64;
    let r = split.reverse as f64;
    let k = settings.light_samples.max(1) as f64;
    let surface = (layout.slot_count - layout.surface_slots().start) as f64;
    let connections = if settings.connections == 0 {
        surface
    } else {
        surface.min(settings.connections as f64)
    };
    let depth = settings.depth.max(1) as f64;
    let reverse = r * (1.0 + settings.pool as f64) + r * k * (1.0 + 2.0 * depth + connections);
    // find_uncovered_vpls.comp under `both`: at most M per standard VPL.
    let coverage = if r > 0.0 {
        standard_count as f64 * settings.pool as f64
    } else {
        0.0
    };
    let power = if resampling {
        (standard_count as f64 + r) * settings.power_samples as f64
    } else {
        0.0
    };
    walk + reverse + coverage + power
}
