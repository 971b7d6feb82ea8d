//! Sequences of animated scenes (src/scene/animation.rs, src/sequence.rs; docs/DESIGN.md
//! "Animation"): a point light moving over a diffuse plane matches its closed form in every
//! frame; frame f of a sequence has the bits of a still render of frame f; an interrupted
//! sequence resumes to the files of one run through, and a folder of another sequence is
//! refused.

use crate::common;

use std::path::{Path, PathBuf};

use glam::Vec3;
use irad::image::exr;
use irad::methods::Method;
use irad::render::{self, RenderJob};
use irad::scene;
use irad::sequence::{self, SequenceJob};

use common::{with_gpu, Scratch};

const ALBEDO: f32 = 0.5;
const INTENSITY: f32 = 2.0;
const HEIGHT: f32 = 0.5;
const FRAMES: u32 = 5;

/// A diffuse plane (y = 0, 4 x 4) seen from above, a point light 0.5 above it moving from
/// x = -1 to x = 1 over 5 frames at 4 fps (linear: x = -1 + f / 2).
fn moving_light(dir: &Path) -> scene::Scene {
    std::fs::write(
        dir.join("plane.obj"),
        "mtllib plane.mtl\nv -2 0 -2\nv 2 0 -2\nv 2 0 2\nv -2 0 2\nusemtl floor\nf 1 4 3 2\n",
    )
    .unwrap();
    std::fs::write(
        dir.join("plane.mtl"),
        format!("newmtl floor\nKd {ALBEDO} {ALBEDO} {ALBEDO}\n"),
    )
    .unwrap();
    let toml = format!(
        "[camera]\nposition = [0, 4, 0.001]\nlook_at = [0, 0, 0]\nfov_y = 40\n\
         resolution = [16, 16]\n[[mesh]]\nobj = \"plane.obj\"\n\
         [[light]]\nkind = \"point\"\nposition = [-1, {HEIGHT}, 0]\n\
         intensity = [{INTENSITY}, {INTENSITY}, {INTENSITY}]\n\
         [animation]\nframes = {FRAMES}\nfps = 4\n[[animation.track]]\n\
         target = \"light[0].position\"\ntimes = [0.0, 1.0]\n\
         values = [[-1, {HEIGHT}, 0], [1, {HEIGHT}, 0]]\n"
    );
    std::fs::write(dir.join("scene.toml"), toml).unwrap();
    scene::load(&dir.join("scene.toml")).unwrap()
}

fn path_tracer(spp: u32, seed: u32) -> Method {
    let params: toml::Table = toml::from_str(&format!(
        "spp = {spp}\nseed = {seed}\nmax_depth = 1\npixel_centres = true"
    ))
    .unwrap();
    Method::from_params("reference", &params).unwrap()
}

/// Each pixel centre's radiance: (rho / pi) I cos / d^2 with cos = h / d, from the point its
/// camera ray meets on the plane. With pixel centres and a point light, next-event estimation
/// is exact and BSDF samples never meet the light, so the render has no noise.
#[test]
fn a_point_light_moving_over_a_plane_matches_its_closed_form_in_every_frame() {
    let dir = Scratch::new("seq", "closed-form");
    let scene = moving_light(&dir.0);
    with_gpu(|ctx| {
        let mut frames_seen = 0;
        sequence::render_frames(
            ctx,
            &scene,
            &path_tracer(2, 7),
            0..FRAMES,
            |f, still, out| {
                let light = Vec3::new(-1.0 + f as f32 / 2.0, HEIGHT, 0.0);
                let cam = &still.camera;
                let mut worst = 0.0f64;
                for j in 0..cam.height {
                    for i in 0..cam.width {
                        let d = cam.direction(i as f32 + 0.5, j as f32 + 0.5);
                        let hit = cam.position + d * (-cam.position.y / d.y);
                        let to_light = light - hit;
                        let dist2 = to_light.length_squared() as f64;
                        let cos = HEIGHT as f64 / dist2.sqrt();
                        let expected =
                            ALBEDO as f64 / std::f64::consts::PI * INTENSITY as f64 * cos / dist2;
                        let got = out.image.pixels[(j * cam.width + i) as usize][1] as f64;
                        worst = worst.max((got / expected - 1.0).abs());
                    }
                }
                eprintln!(
                    "frame {f}: light at x = {}, worst relative error {worst:.2e}",
                    light.x
                );
                assert!(worst < 1e-3, "frame {f}: {worst}");
                frames_seen += 1;
                Ok(())
            },
        )
        .unwrap();
        assert_eq!(frames_seen, FRAMES);

        // The animated scene whole (the file's own values, not a frame's) is refused.
        let gpu = irad::scene::gpu::GpuScene::upload(ctx, &scene).unwrap();
        let e = irad::methods::Renderers::default()
            .run(ctx, &path_tracer(1, 0), &scene, &gpu, |_, _| {})
            .err()
            .unwrap()
            .to_string();
        assert!(
            e.contains("is animated (5 frames)") && e.contains("--frame N"),
            "{e}"
        );
    });
}

/// A resolution set on the loaded scene (a suite's width, a test's size) holds in every frame.
#[test]
fn frames_keep_the_resolution_the_scene_was_given() {
    let dir = Scratch::new("seq", "resolution");
    let mut scene = moving_light(&dir.0);
    (scene.camera.width, scene.camera.height) = (8, 4);
    let still = scene.at_frame(2).unwrap();
    assert_eq!((still.camera.width, still.camera.height), (8, 4));
}

/// Frame f of `render_sequence` against `irad render --frame f`'s path (the frame's still
/// scene, the frame's seed), bit for bit; then a run cut after two frames and resumed leaves
/// the same images and records as one run through, and another sequence's folder is refused.
#[test]
fn frames_are_stills_and_an_interrupted_sequence_resumes_to_the_same_files() {
    let dir = Scratch::new("seq", "resume");
    let scene = moving_light(&dir.0);
    let method = path_tracer(2, 3).with_count(2);
    let jittered: toml::Table = toml::from_str("spp = 2\nseed = 3").unwrap();
    let jittered = Method::from_params("reference", &jittered).unwrap();
    with_gpu(|ctx| {
        let scored = |out: &Path,
                      frames: std::ops::Range<u32>,
                      method: &Method,
                      reference: Option<PathBuf>| {
            let job = SequenceJob {
                scene: &scene,
                method: method.clone(),
                frames,
                out: out.to_path_buf(),
                exposure: 0.0,
                flip: reference.is_some(),
                reference,
            };
            sequence::render_sequence(ctx, &job, |_| {}, |_, _| {})
        };
        let run = |out: &Path, frames: std::ops::Range<u32>, method: &Method| {
            scored(out, frames, method, None)
        };
        let whole = dir.0.join("whole");
        let report = run(&whole, 0..FRAMES, &jittered).unwrap();
        assert_eq!(report.record.rendered.len(), FRAMES as usize);
        assert!(report.resumed.is_empty());
        assert!(whole.join("preview.png").exists());

        // Frame 3 as a still.
        let still = scene.at_frame(3).unwrap();
        let job = RenderJob {
            scene: &still,
            method: sequence::frame_method(&jittered, 3),
            out: dir.0.join("still"),
            exposure: 0.0,
            reference: None,
            frame: Some(3),
        };
        let alone = render::render(ctx, &job, |_, _| {}).unwrap();
        let in_sequence =
            exr::read(&sequence::frame_stem(&whole, 3).with_extension("exr")).unwrap();
        assert_eq!(alone.image.pixels, in_sequence.pixels, "frame 3");
        let frame2 = exr::read(&sequence::frame_stem(&whole, 2).with_extension("exr")).unwrap();
        assert_ne!(
            frame2.pixels, in_sequence.pixels,
            "frames 2 and 3 are the same image"
        );

        // Cut after frames 0 and 1 (their files complete, the rest never written), resumed.
        let cut = dir.0.join("cut");
        run(&cut, 0..2, &jittered).unwrap();
        std::fs::remove_file(cut.join("sequence.json")).unwrap();
        // Frame 2 cut short: an image without its JSON (written last) is not a complete frame.
        std::fs::write(sequence::frame_stem(&cut, 2).with_extension("exr"), b"half").unwrap();
        let resumed = run(&cut, 0..FRAMES, &jittered).unwrap();
        assert_eq!(resumed.resumed, vec![0, 1]);
        for f in 0..FRAMES {
            let stem = |d: &Path| sequence::frame_stem(d, f);
            let a = exr::read(&stem(&whole).with_extension("exr")).unwrap();
            let b = exr::read(&stem(&cut).with_extension("exr")).unwrap();
            assert_eq!(a.pixels, b.pixels, "frame {f}");
            let ra = irad::image::RenderRecord::read(&stem(&whole).with_extension("json")).unwrap();
            let rb = irad::image::RenderRecord::read(&stem(&cut).with_extension("json")).unwrap();
            assert_eq!(
                (ra.seed, ra.frame, &ra.parameters),
                (rb.seed, rb.frame, &rb.parameters)
            );
        }
        let frames =
            |r: &sequence::SequenceRecord| r.rendered.iter().map(|f| f.frame).collect::<Vec<_>>();
        assert_eq!(frames(&resumed.record), frames(&report.record));

        // Scored against its own frames (the same bits): no error and no flicker; against the
        // pixel-centred frames, an error in every frame and a flicker.
        let same = scored(
            &dir.0.join("same"),
            0..FRAMES,
            &jittered,
            Some(whole.clone()),
        )
        .unwrap();
        let m = same.record.metrics.unwrap();
        assert_eq!(
            (m.mean.rel_mse, m.worst_rel_mse, m.flicker, m.mean.flip),
            (0.0, 0.0, 0.0, Some(0.0))
        );
        assert!(same
            .record
            .rendered
            .iter()
            .all(|f| f.metrics.as_ref().unwrap().rel_mse == 0.0));
        let centres = dir.0.join("centres");
        run(&centres, 0..FRAMES, &method).unwrap();
        let other = scored(&dir.0.join("other"), 0..FRAMES, &jittered, Some(centres)).unwrap();
        let m = other.record.metrics.unwrap();
        assert!(m.mean.rel_mse > 0.0 && m.flicker > 0.0, "{m:?}");
        // HDR-FLIP per frame: each frame's and their mean.
        assert!(m.mean.flip.is_some_and(|f| f > 0.0 && f < 1.0), "{m:?}");
        assert!(other
            .record
            .rendered
            .iter()
            .all(|f| f.metrics.as_ref().unwrap().flip.is_some()));
        assert!(m.worst_rel_mse >= m.mean.rel_mse);

        // Another sequence (other samples a frame) into the same folder: refused, files kept.
        let e = run(&cut, 0..FRAMES, &method).err().unwrap().to_string();
        assert!(
            e.contains("holds frames of another sequence") && e.contains("pixel_centres"),
            "{e}"
        );
    });
}

/// A method that renders nothing and writes down what the driver hands its `set_up`: the
/// frame, the previous frame's number, its camera and light, and what changed.
mod probe {
    use std::sync::Mutex;

    use irad::gpu::{Commands, Context, GpuResult};
    use irad::methods::gbuffer::PixelSampling;
    use irad::methods::settings::{Kind, Setting, Value};
    use irad::methods::{
        AcrossFrames, AnimationFrame, Carried, Change, Lights, MethodFrames, RenderMethod, Shared,
        SharedPasses, Support,
    };
    use irad::scene::gpu::GpuScene;
    use irad::scene::{Light, Scene};

    /// (frame, previous frame, the previous frame's light position, changes) per set_up.
    pub type Seen = (u32, Option<u32>, Option<[f32; 3]>, Vec<&'static str>);
    pub static SEEN: Mutex<Vec<Seen>> = Mutex::new(Vec::new());

    pub struct Probe;

    #[derive(Clone, Debug, PartialEq, Default)]
    pub struct ProbeSettings {
        frames: u32,
        seed: u32,
    }

    const SETTINGS: &[Setting<ProbeSettings>] = &[
        Setting::new(
            "frames",
            Kind::Count { min: 1, max: 4 },
            "Frames.",
            |s| Some(Value::Count(s.frames)),
            |s, v| s.frames = v.count(),
        ),
        Setting::new(
            "seed",
            Kind::Count {
                min: 0,
                max: u32::MAX,
            },
            "Seed.",
            |s| Some(Value::Count(s.seed)),
            |s, v| s.seed = v.count(),
        ),
    ];

    impl RenderMethod for Probe {
        type Settings = ProbeSettings;
        const NAME: &'static str = "probe";
        const SUMMARY: &'static str = "Writes down what the driver hands it.";
        const SETTINGS: &'static [Setting<ProbeSettings>] = SETTINGS;
        const COUNT: &'static str = "frames";
        const LIGHTS: Lights = Lights {
            environment: Support::Renders,
            area: Support::Renders,
            point: Support::Renders,
            luminaires: Support::Renders,
        };
        const ACROSS_FRAMES: AcrossFrames = AcrossFrames {
            carries: &[Carried {
                state: "nothing real (a test)",
                invalidated_by: &[Change::Lights],
            }],
        };

        fn new(_ctx: &Context) -> GpuResult<Self> {
            Ok(Probe)
        }

        fn shared_passes(_settings: &ProbeSettings) -> SharedPasses {
            SharedPasses {
                pixels: PixelSampling::Centres,
                direct: None,
            }
        }

        fn set_up<'a>(
            &'a self,
            _ctx: &Context,
            scene: &Scene,
            _gpu_scene: &GpuScene,
            _settings: &'a ProbeSettings,
            animation: &AnimationFrame<'_>,
        ) -> GpuResult<Box<dyn MethodFrames + 'a>> {
            let light = |s: &Scene| match s.lights[0] {
                Light::Point { position, .. } => position.to_array(),
                _ => unreachable!(),
            };
            let previous = animation.previous.as_ref();
            if let Some(p) = previous {
                // The previous frame's scene is the one at_frame gives, not this frame's.
                assert_ne!(light(p.scene), light(scene));
            }
            // The light moves every frame, and the state is invalidated by lights.
            assert!(!animation.keeps(&Self::ACROSS_FRAMES.carries[0]));
            SEEN.lock().unwrap().push((
                animation.frame,
                previous.map(|p| p.frame),
                previous.map(|p| light(p.scene)),
                previous.map_or(vec![], |p| p.changed.iter().map(Change::name).collect()),
            ));
            Ok(Box::new(Nothing))
        }
    }

    struct Nothing;

    impl MethodFrames for Nothing {
        fn record<'a>(
            &'a self,
            _shared: &Shared<'a>,
            _cmd: &mut Commands<'a>,
            _frame: u32,
        ) -> GpuResult<()> {
            Ok(())
        }
    }
}

/// The driver hands a method each frame with the previous frame's scene and what changed
/// (the light moves, nothing else), in `render_frames` and `render_sequence`; a frame kept
/// from an earlier run leaves the next without a previous frame, and a method that carries
/// state is warned of it.
#[test]
fn the_driver_hands_each_frame_the_previous_frames_scene() {
    let dir = Scratch::new("seq", "probe");
    let scene = moving_light(&dir.0);
    let registry = irad::methods::Registry::builtin()
        .clone()
        .with::<probe::Probe>();
    let method = registry
        .from_params("probe", &toml::from_str("frames = 1").unwrap())
        .unwrap();
    assert_eq!(
        method.across_frames().describe(),
        "nothing real (a test) (invalidated by a change of lights)"
    );
    let x = |f: u32| -1.0 + f as f32 / 2.0;
    let seen = || std::mem::take(&mut *probe::SEEN.lock().unwrap());
    with_gpu(|ctx| {
        seen();
        sequence::render_frames(ctx, &scene, &method, 1..4, |_, _, _| Ok(())).unwrap();
        let got = seen();
        assert_eq!(got.len(), 3);
        assert_eq!(got[0], (1, None, None, vec![]), "the first frame rendered");
        for (k, f) in [2u32, 3].into_iter().enumerate() {
            assert_eq!(
                got[k + 1],
                (
                    f,
                    Some(f - 1),
                    Some([x(f - 1), HEIGHT, 0.0]),
                    vec!["lights"]
                ),
                "frame {f}"
            );
        }

        // Frames 0 and 1 rendered, then 0..4 resumed: 2 starts without a previous frame
        // (1 was kept from disk), 3 gets 2.
        let out = dir.0.join("probe-sequence");
        let job = |frames| SequenceJob {
            scene: &scene,
            method: method.clone(),
            frames,
            out: out.clone(),
            exposure: 0.0,
            reference: None,
            flip: false,
        };
        let mut events = vec![];
        sequence::render_sequence(ctx, &job(0..2), |p| events.push(p), |_, _| {}).unwrap();
        // Per frame its start and its samples as they complete, then the end.
        let brief: Vec<(u32, u32, u32)> = events
            .iter()
            .map(|p| (p.frames_done, p.frame, p.samples_done))
            .collect();
        assert_eq!(
            brief,
            [(0, 0, 0), (0, 0, 1), (1, 1, 0), (1, 1, 1), (2, 2, 0)],
            "{events:?}"
        );
        seen();
        let report = sequence::render_sequence(ctx, &job(0..4), |_| {}, |_, _| {}).unwrap();
        assert_eq!(report.resumed, [0, 1]);
        let got = seen();
        assert_eq!(got[0], (2, None, None, vec![]));
        assert_eq!(got[1].1, Some(2));
        assert!(
            report
                .warnings
                .iter()
                .any(|w| w.contains("probe carries state across frames") && w.contains("frame 2")),
            "{:?}",
            report.warnings
        );

        // A range that starts after frame 0 starts without state, and says so.
        let out = dir.0.join("probe-range");
        let job = SequenceJob {
            out: out.clone(),
            ..job(2..3)
        };
        let report = sequence::render_sequence(ctx, &job, |_| {}, |_, _| {}).unwrap();
        assert!(
            report
                .warnings
                .iter()
                .any(|w| w.contains("frame 2, the first of a range that starts after frame 0")),
            "{:?}",
            report.warnings
        );
    });
}

/// Every built-in method renders a sequence frame by frame (the baseline: each frame on its
/// own), on the first shipped animated scene whose lights it renders: each frame finite and
/// lit, frames 0 and 1 different images, and frame 1 the bits of frame 1 rendered alone.
#[test]
fn every_builtin_method_renders_an_animated_scene_frame_by_frame() {
    let scenes = [
        "cornell-circling",
        "moving-sun-sequence",
        "car-headlights-sweep",
    ]
    .map(|name| common::scene_file(name, 16, 12));
    let registry = irad::methods::Registry::builtin();
    with_gpu(|ctx| {
        for name in registry.names() {
            let method = registry
                .from_params(name, &toml::Table::new())
                .unwrap()
                .with_count(2)
                .with_seed(5);
            let Some(scene) = scenes
                .iter()
                .find(|s| method.declines(&s.at_frame(0).unwrap()).is_none())
            else {
                panic!("{name} renders none of the shipped animated scenes");
            };
            let mut images = vec![];
            sequence::render_frames(ctx, scene, &method, 0..2, |f, _, out| {
                let mean = common::luminance_mean(&out.image);
                assert!(
                    mean.is_finite() && mean > 0.0,
                    "{name} frame {f} of {}: mean {mean}",
                    scene.name
                );
                assert_eq!(out.nonfinite_estimates, 0, "{name} frame {f}");
                images.push(out.image);
                Ok(())
            })
            .unwrap();
            assert_ne!(images[0].pixels, images[1].pixels, "{name}: frames 0 and 1");
            let still = scene.at_frame(1).unwrap();
            let gpu = irad::scene::gpu::GpuScene::upload(ctx, &still).unwrap();
            let alone = irad::methods::Renderers::default()
                .run_frame(
                    ctx,
                    &sequence::frame_method(&method, 1),
                    &still,
                    &gpu,
                    &irad::methods::AnimationFrame::alone(1),
                    |_, _| {},
                )
                .unwrap();
            // A method that keeps nothing across frames renders frame 1 alone to the same bits;
            // one that keeps state (restir's reservoirs) uses frame 0's in the sequence.
            if method.across_frames().carries_nothing() {
                assert_eq!(
                    alone.image.pixels, images[1].pixels,
                    "{name}: frame 1 alone"
                );
            } else {
                assert_ne!(
                    alone.image.pixels, images[1].pixels,
                    "{name}: frame 1 alone, as if frame 0's state were not reused"
                );
            }
            eprintln!("{name}: {} frames 0 and 1 rendered", scene.name);
        }
    });
}
