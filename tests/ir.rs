//! Instant radiosity (Keller 97): the walk's survivor counts, and the estimator against
//! the reference.

use crate::common;

use glam::Vec3;
use irad::gpu::{Commands, Context};
use irad::image::Image;
use irad::methods::compensation::{ClampSettings, VplClamp};
use irad::methods::gbuffer::PixelSampling;
use irad::methods::ir::schedule::{Absorption, Schedule};
use irad::methods::ir::walk::{TraceVpls, VplBuffers, VPL_NONE};
use irad::methods::ir::{DirectLight, InstantRadiosity, IrSettings};
use irad::methods::reference::{Reference, ReferenceSettings};
use irad::methods::Renderer;
use irad::scene::gpu::GpuScene;
use irad::scene::{Light, Scene};

use common::shapes::*;
use common::{luminance_mean, mean_and_stderr, with_gpu};

/// A closed sphere of albedo 0.5 everywhere, lit by a point light inside: every walk stays
/// inside, so exactly floor(0.5^j N) paths reach vertex j, and past the last (N_j = 1) that
/// path goes on by roulette.
#[test]
fn walk_reproduces_kellers_survivor_counts() {
    with_gpu(|ctx| {
        let mut scene = scene(
            "closed sphere",
            camera(Vec3::ZERO, Vec3::new(0.0, 0.0, -1.0), Vec3::Y, 60.0, 8),
            sphere(1.0, 16, 32, true, 0),
            vec![material("wall", 0.5, 0.0, 1.0, 0.0)],
        );
        scene.lights.push(Light::Point {
            position: Vec3::new(0.1, 0.2, 0.0),
            intensity: Vec3::ONE,
        });
        let n = 1000;
        let rho = irad::methods::ir::schedule::mean_albedo(&scene);
        assert!((rho - 0.5).abs() < 1e-6, "mean albedo {rho}");
        let schedule = Schedule::new(n, rho, Absorption::Fractional);
        let gpu = GpuScene::upload(ctx, &scene).unwrap();
        let buffers = VplBuffers::new(ctx, schedule.clone()).unwrap();
        let walk = TraceVpls::new(ctx).unwrap();
        let mut cmd = Commands::new(ctx).unwrap();
        walk.record(&mut cmd, &gpu, &buffers, 3, None).unwrap();
        cmd.submit_and_wait().unwrap();
        let vpls = buffers.vpls.read().unwrap();
        let alive_at = |level: &[u32; 4]| {
            vpls[level[1] as usize..(level[1] + level[0]) as usize]
                .iter()
                .filter(|v| v.kind() != VPL_NONE)
                .count()
        };
        let fractional = schedule.levels.iter().take_while(|l| l[3] == 0).count();
        assert_eq!(fractional, 10);
        for (j, level) in schedule.levels[..fractional].iter().enumerate() {
            let expected = (0.5f64.powi(j as i32) * n as f64).floor() as usize;
            assert_eq!(level[0] as usize, expected, "schedule at vertex {j}");
            assert_eq!(alive_at(level), expected, "VPLs at vertex {j}");
        }
        // The roulette tail: the last path reaches its first vertex surely, then each next one
        // with probability 1/2 (the wall's albedo), and once dead stays dead.
        let tail: Vec<usize> = schedule.levels[fractional..].iter().map(alive_at).collect();
        assert_eq!(tail.len(), 10);
        assert_eq!(tail[0], 1, "the tail's first vertex");
        assert!(
            tail.windows(2).all(|w| w[1] <= w[0]),
            "tail survivors {tail:?}"
        );
    });
}

fn small_cornell() -> Scene {
    let mut scene = irad::scene::default_scene();
    scene.camera.width = 64;
    scene.camera.height = 64;
    scene
}

fn reference(ctx: &Context, scene: &Scene, spp: u32, pixels: PixelSampling) -> Image {
    let gpu = GpuScene::upload(ctx, scene).unwrap();
    let settings = ReferenceSettings {
        spp,
        seed: 1234,
        pixels,
        ..Default::default()
    };
    Renderer::<Reference>::new(ctx)
        .unwrap()
        .render(ctx, scene, &gpu, &settings, |_, _| {})
        .unwrap()
        .image
}

fn ir(ctx: &Context, scene: &Scene, settings: &IrSettings) -> Image {
    let gpu = GpuScene::upload(ctx, scene).unwrap();
    let out = Renderer::<InstantRadiosity>::new(ctx)
        .unwrap()
        .render(ctx, scene, &gpu, settings, |_, _| {})
        .unwrap();
    assert_eq!(out.nonfinite_estimates, 0);
    out.image
}

/// (a) ir at its defaults (b from the scene, compensated) converges to the reference: the mean
/// over 16 seeds is within 1%. (d) So
/// does interleaved sampling with k = 4 and its filter; the error the filter adds (or removes)
/// is reported as relMSE against the reference next to k = 1.
#[test]
#[ignore = "statistical tier: scripts/test.sh --statistical"]
fn ir_mean_matches_the_reference_with_and_without_interleaving() {
    with_gpu(|ctx| {
        // 32x32 (4x4 interleaving tiles still fit many times): the image mean's spread over
        // seeds comes from each render's VPLs, shared by every pixel (64x64 took 102 s of CI).
        let mut scene = small_cornell();
        scene.camera.width = 32;
        scene.camera.height = 32;
        let reference_image = reference(ctx, &scene, 512, PixelSampling::Jittered);
        let r = luminance_mean(&reference_image);
        for k in [1u32, 4] {
            let images: Vec<Image> = (0..16)
                .map(|seed| {
                    let settings = IrSettings {
                        paths: 256,
                        frames: 4,
                        seed,
                        interleave: k,
                        ..Default::default()
                    };
                    ir(ctx, &scene, &settings)
                })
                .collect();
            let means: Vec<f64> = images.iter().map(luminance_mean).collect();
            let (mean, stderr) = mean_and_stderr(&means);
            let e = images
                .iter()
                .map(|i| rel_mse(i, &reference_image))
                .sum::<f64>()
                / 16.0;
            eprintln!(
                "interleave {k}: ir mean / reference mean = {:.5} (standard error {:.5}), mean relMSE {e:.4e}",
                mean / r,
                stderr / r
            );
            assert!(stderr / r < 0.004, "too noisy to test at 1%");
            assert!(
                (mean / r - 1.0).abs() < 0.01,
                "k {k}: ir mean {mean}, reference {r}"
            );
        }
    });
}

fn rel_mse(x: &Image, r: &Image) -> f64 {
    irad::image::compare(x, r).unwrap().rel_mse
}

/// Pixels whose camera ray (centre) meets the Cornell box's walls within 0.1 of two of its
/// planes in the upper half (the ceiling's and the walls' edges, where no block stands):
/// where the geometry term's weak singularity lives.
fn corner_pixels(scene: &Scene) -> Vec<usize> {
    let cam = &scene.camera;
    let mut out = Vec::new();
    for y in 0..cam.height {
        for x in 0..cam.width {
            let d = cam.direction(x as f32 + 0.5, y as f32 + 0.5);
            let o = cam.position;
            // Nearest wall plane along the ray, inside the box [-1,1] x [0,2] x [-1,1].
            let mut t_hit = f32::INFINITY;
            for (axis, value) in [(0, -1.0), (0, 1.0), (1, 0.0), (1, 2.0), (2, -1.0)] {
                let t = (value - o[axis]) / d[axis];
                let p = o + d * t;
                if t > 0.0 && t < t_hit && p.z <= 1.0 && p.z >= -1.001 && p.x.abs() <= 1.001 {
                    t_hit = t;
                }
            }
            let p = o + d * t_hit;
            let near = [1.0 - p.x.abs(), p.y, 2.0 - p.y, p.z + 1.0]
                .iter()
                .filter(|e| e.abs() < 0.1)
                .count();
            if t_hit.is_finite() && near >= 2 && p.y > 1.2 {
                out.push((y * cam.width + x) as usize);
            }
        }
    }
    out
}

/// (b) error falls with the VPL budget; (c) the geometry clamp trades a measured darkening in
/// the corners for lower error at a small budget.
#[test]
#[ignore = "statistical tier: scripts/test.sh --statistical"]
fn error_falls_with_vpls_and_clamping_darkens_corners() {
    with_gpu(|ctx| {
        // 32x32, a quarter of the pixels (64x64 before: relMSE fell 11.2x, 4x asserted; the
        // clamped corners 0.917 +- 0.008 of the reference over 264 pixels). Measured at 32x32:
        // relMSE fell 9.8x, the clamp halved it at 64 paths, and 70 corner pixels came out
        // 0.921 +- 0.008, 10 standard errors below 1 where 3 are asserted.
        let mut scene = small_cornell();
        scene.camera.width = 32;
        scene.camera.height = 32;
        // Pixel centres in both: the error measured is light transport only, not the
        // pixel-footprint noise of one jittered sample per pixel.
        let r = reference(ctx, &scene, 1024, PixelSampling::Centres);
        let seeds = 0..4u32;
        // Keller's original (light vertices as VPLs): every light path goes through VPLs, so
        // the error measured is the VPLs' (next-event direct light at 1 sample per pixel would
        // add a floor that does not fall with the VPL count).
        let run = |paths: u32, g_clamp: f32| -> (f64, Vec<Image>) {
            let images: Vec<Image> = seeds
                .clone()
                .map(|seed| {
                    let settings = IrSettings {
                        paths,
                        frames: 1,
                        seed: 100 + seed,
                        // The plain clamp (its bias is what the test measures), or none.
                        clamp: ClampSettings {
                            clamp: VplClamp::Fixed(g_clamp),
                            compensate: false,
                        },
                        direct: DirectLight::Vpl,
                        pixels: PixelSampling::Centres,
                        // One direct sample a frame (the G-buffer's hit), as measured: the
                        // test is about the VPLs, and more direct samples only cost time.
                        direct_spp: 1,
                        ..Default::default()
                    };
                    ir(ctx, &scene, &settings)
                })
                .collect();
            let e = images.iter().map(|i| rel_mse(i, &r)).sum::<f64>() / images.len() as f64;
            (e, images)
        };
        let (e64, _) = run(64, 0.0);
        let (e1024, _) = run(1024, 0.0);
        let slope = (e1024 / e64).ln() / 16f64.ln();
        eprintln!(
            "relMSE: 64 paths {e64:.4e}, 1024 paths {e1024:.4e}, ratio {:.2}, slope {slope:.2} (ideal -1)",
            e64 / e1024
        );
        assert!(e64 / e1024 >= 4.0, "relMSE fell only {:.2}x", e64 / e1024);

        let g_clamp = 10.0;
        let (e64_clamped, _) = run(64, g_clamp);
        eprintln!(
            "relMSE at 64 paths: unclamped {e64:.4e}, clamped at G <= {g_clamp}: {e64_clamped:.4e}"
        );
        assert!(e64_clamped < e64);

        // The darkening is a bias: measure it where the noise is small, at 1024 paths.
        let (_, clamped) = run(1024, g_clamp);
        let corners = corner_pixels(&scene);
        assert!(corners.len() > 20, "{} corner pixels", corners.len());
        let lum = |p: [f32; 3]| 0.2126 * p[0] as f64 + 0.7152 * p[1] as f64 + 0.0722 * p[2] as f64;
        let ratios: Vec<f64> = clamped
            .iter()
            .map(|img| {
                let x: f64 = corners.iter().map(|&i| lum(img.pixels[i])).sum();
                let y: f64 = corners.iter().map(|&i| lum(r.pixels[i])).sum();
                x / y
            })
            .collect();
        let n = ratios.len() as f64;
        let mean = ratios.iter().sum::<f64>() / n;
        let stderr =
            (ratios.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1.0) / n).sqrt();
        eprintln!(
            "clamped / reference in {} corner pixels: {mean:.4} (standard error {stderr:.4})",
            corners.len()
        );
        assert!(
            mean < 1.0 - 3.0 * stderr,
            "the clamp should darken the corners"
        );
    });
}

/// Both absorption schemes are unbiased (unclamped): inside a closed diffuse sphere lit by a point
/// light (every path bounces until absorbed), the ir mean over 8 seeds is within 1% of the
/// reference, with fractional absorption and with Russian roulette.
#[test]
#[ignore = "statistical tier: scripts/test.sh --statistical"]
fn fractional_and_roulette_absorption_match_the_reference() {
    with_gpu(|ctx| {
        let mut scene = scene(
            "closed sphere",
            // 12 pixels wide: the image mean's spread over seeds comes from each render's VPLs,
            // which every pixel shares (at 24 wide this test took 213 s of CI, nearly all in
            // the gather's shadow rays inside the closed sphere). Measured at 12: fractional
            // 1.0034 +- 0.0020, roulette 1.0003 +- 0.0037 of the reference.
            camera(Vec3::ZERO, Vec3::new(0.3, -0.2, -1.0), Vec3::Y, 70.0, 12),
            sphere(1.0, 12, 24, true, 0),
            vec![material("wall", 0.6, 0.0, 1.0, 0.0)],
        );
        scene.lights.push(Light::Point {
            position: Vec3::new(0.2, 0.3, 0.1),
            intensity: Vec3::ONE,
        });
        let r = luminance_mean(&reference(ctx, &scene, 1024, PixelSampling::Jittered));
        for absorption in [Absorption::Fractional, Absorption::Roulette] {
            let means: Vec<f64> = (0..8)
                .map(|seed| {
                    let settings = IrSettings {
                        paths: 1024,
                        frames: 4,
                        seed,
                        absorption,
                        // Unclamped: the estimator both schemes feed, without the clamp.
                        clamp: ClampSettings {
                            clamp: VplClamp::Fixed(0.0),
                            compensate: false,
                        },
                        // One direct sample a frame (the G-buffer's hit), as measured: the
                        // test is about the VPLs, and more direct samples only cost time.
                        direct_spp: 1,
                        ..Default::default()
                    };
                    luminance_mean(&ir(ctx, &scene, &settings))
                })
                .collect();
            let (mean, stderr) = mean_and_stderr(&means);
            eprintln!(
                "{absorption:?}: ir mean / reference mean = {:.5} (standard error {:.5})",
                mean / r,
                stderr / r
            );
            assert!(stderr / r < 0.004, "too noisy to test at 1%");
            assert!(
                (mean / r - 1.0).abs() < 0.01,
                "{absorption:?}: {mean} vs {r}"
            );
        }
    });
}
