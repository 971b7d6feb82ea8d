//! Bidirectional instant radiosity (Segovia 06): each strategy's estimator against the reference.

use crate::common;

use irad::gpu::Context;
use irad::methods::bir::{Bir, BirSettings, Strategy};
use irad::methods::compensation::{ClampSettings, VplClamp};
use irad::methods::reference::{Reference, ReferenceSettings};
use irad::methods::Renderer;
use irad::scene::gpu::GpuScene;
use irad::scene::Scene;

use common::{luminance_mean, mean_and_stderr, scene_file, with_gpu};

fn small_cornell(size: u32) -> Scene {
    let mut scene = irad::scene::default_scene();
    scene.camera.width = size;
    scene.camera.height = size;
    scene
}

fn reference_mean(ctx: &Context, scene: &Scene, spp: u32) -> f64 {
    let gpu = GpuScene::upload(ctx, scene).unwrap();
    let settings = ReferenceSettings {
        spp,
        seed: 4321,
        ..Default::default()
    };
    let out = Renderer::<Reference>::new(ctx)
        .unwrap()
        .render(ctx, scene, &gpu, &settings, |_, _| {})
        .unwrap();
    luminance_mean(&out.image)
}

/// Standard, reverse and both, resampled (r = 10, the uniform floor) and not, converge to the
/// reference in the Cornell box: the image mean over 16 seeds within 1.5% (the standard error
/// checked small enough for that to mean something). Breaking the reverse density (dropping
/// Eq. 7's 1 / M), the 1/2 weights of `both` or the resampling weight 1 / (N' q) moves the mean
/// by far more.
#[test]
#[ignore = "statistical tier: scripts/test.sh --statistical"]
fn every_strategy_matches_the_reference_mean_in_the_cornell_box() {
    with_gpu(|ctx| {
        // 32x32: the image mean's spread over seeds comes from each render's VPLs, shared by
        // every pixel, so a quarter of the pixels leaves it about where it was (at 64x64 this
        // test took 255 s of CI).
        let scene = small_cornell(32);
        // 1024 samples per pixel (4096 before): measured over 6 seeds at 512, one render's
        // image mean varies by 0.098%, so by about 0.07% here, a twentieth of the smallest
        // standard error below and a twentieth of the 1.5% tested.
        let r = reference_mean(ctx, &scene, 1024);
        let gpu = GpuScene::upload(ctx, &scene).unwrap();
        let bir = Renderer::<Bir>::new(ctx).unwrap();
        let cases = [
            (Strategy::Standard, 10),
            (Strategy::Reverse, 10),
            (Strategy::Both, 10),
            (Strategy::Both, 0),
        ];
        for (strategy, ratio) in cases {
            let means: Vec<f64> = (0..16)
                .map(|seed| {
                    let settings = BirSettings {
                        vpls: if ratio > 0 { 512 } else { 256 },
                        // 8 frames resampled (16 before: standard errors 0.0011 to 0.0017 of
                        // the mean; at 8 measured 0.0023 to 0.0033, unresampled's 0.0033 as
                        // before): under the 0.005 checked, so a 2.5% bias fails the 1.5%
                        // test by 3 of them, and the broken weights (2x) by hundreds.
                        frames: if ratio > 0 { 8 } else { 4 },
                        seed: 100 + seed,
                        strategy,
                        ratio,
                        // Unresampled in two batches: each batch's compensation weighs its
                        // share of the direct light at the paths' vertices.
                        batch: if ratio > 0 { 0 } else { 128 },
                        ..Default::default()
                    };
                    let out = bir.render(ctx, &scene, &gpu, &settings, |_, _| {}).unwrap();
                    assert_eq!(out.nonfinite_estimates, 0);
                    luminance_mean(&out.image)
                })
                .collect();
            let (mean, stderr) = mean_and_stderr(&means);
            eprintln!(
                "{} ratio {ratio}: bir mean / reference mean = {:.5} (standard error {:.5})",
                strategy.name(),
                mean / r,
                stderr / r
            );
            assert!(
                stderr / r < 0.005,
                "{}: too noisy to test at 1.5%",
                strategy.name()
            );
            assert!(
                (mean / r - 1.0).abs() < 0.015,
                "{}: bir mean {mean}, reference {r}",
                strategy.name()
            );
        }
    });
}

/// Segovia 06 Fig. 3: a floor cut into 4 x 4 cells by walls, seen from above, lit by a point
/// light high over it. Each VPL lights only its own cell, a sixteenth of the image, so the
/// power estimate from 5 camera points is zero for most of them: a CDF without the uniform
/// floor never draws those and the image darkens (measured: 22%); with the default floor the
/// mean stays, within 3% at a standard error under 1.2% (measured 0.997, standard error 0.011;
/// 0.981 before `both` gave weight 1 to the standard VPLs no camera pool point reaches).
fn cells() -> Scene {
    use common::shapes::*;
    use glam::Vec3;
    let mut triangles = plane_y(4.0, 0.0, 0);
    // A double-sided wall from a to b (on the floor), height h.
    let mut wall = |a: Vec3, b: Vec3, h: f32| {
        let up = Vec3::new(0.0, h, 0.0);
        let (p0, p1, p2, p3) = (a, b, b + up, a + up);
        triangles.push(flat([p0, p1, p2], 0));
        triangles.push(flat([p0, p2, p3], 0));
        triangles.push(flat([p0, p2, p1], 0));
        triangles.push(flat([p0, p3, p2], 0));
    };
    for i in -1..=1 {
        let c = 2.0 * i as f32;
        wall(Vec3::new(c, 0.0, -4.0), Vec3::new(c, 0.0, 4.0), 1.5);
        wall(Vec3::new(-4.0, 0.0, c), Vec3::new(4.0, 0.0, c), 1.5);
    }
    let mut s = scene(
        "cells",
        camera(Vec3::new(0.0, 9.0, 0.01), Vec3::ZERO, Vec3::Y, 50.0, 32),
        triangles,
        vec![material("white", 0.8, 0.0, 1.0, 0.0)],
    );
    s.lights.push(irad::scene::Light::Point {
        position: Vec3::new(0.3, 6.0, 0.2),
        intensity: Vec3::splat(40.0),
    });
    s
}

#[test]
#[ignore = "statistical tier: scripts/test.sh --statistical"]
fn the_uniform_floor_keeps_the_mean_where_power_estimates_miss_vpls() {
    with_gpu(|ctx| {
        let scene = cells();
        let r = reference_mean(ctx, &scene, 2048);
        let gpu = GpuScene::upload(ctx, &scene).unwrap();
        let bir = Renderer::<Bir>::new(ctx).unwrap();
        let ratio = |floor: f32| {
            let means: Vec<f64> = (0..16)
                .map(|seed| {
                    let settings = BirSettings {
                        vpls: 512,
                        // 8 frames with the floor (16 before: 1.0098 +- 0.0048; at 8 measured
                        // 1.0076 +- 0.0071, under the 0.012 checked, so a 6% bias fails the 3%
                        // test by 4 of them), 4 without it (16: 0.8237 +- 0.0021; at 4
                        // measured 0.8232 +- 0.0044: its 18% darkening stays 17 standard
                        // errors past 0.9).
                        frames: if floor > 0.0 { 8 } else { 4 },
                        seed: 300 + seed,
                        floor,
                        // One direct sample a frame (the G-buffer's hit), as measured: the
                        // test is about the VPLs, and more direct samples only cost time.
                        direct_spp: 1,
                        ..Default::default()
                    };
                    let out = bir.render(ctx, &scene, &gpu, &settings, |_, _| {}).unwrap();
                    luminance_mean(&out.image)
                })
                .collect();
            let (mean, stderr) = mean_and_stderr(&means);
            eprintln!(
                "floor {floor}: bir mean / reference = {:.4} (standard error {:.4})",
                mean / r,
                stderr / r
            );
            (mean / r, stderr / r)
        };
        let (with_floor, e1) = ratio(BirSettings::default().floor);
        let (without, e2) = ratio(0.0);
        // The floor's VPLs are drawn rarely and weigh much: the mean keeps, the noise grows.
        assert!(e1 < 0.012 && e2 < 0.012, "too noisy to tell");
        assert!(
            (with_floor - 1.0).abs() < 0.03,
            "with the floor: {with_floor}"
        );
        assert!(
            without < 0.9,
            "without the floor the image should darken: {without}"
        );
    });
}

/// Segovia 06 Fig. 6 (b): in the halogen office (scenes/failure/halogen-office) the lamp lights
/// a small pool of ceiling that few length-2 camera paths reach, so reverse-only renders rest
/// on the rare reverse VPLs that land in it; `both`, at the same VPL budget, keeps the standard
/// VPLs (which all start in the pool) and weights the starving side down. The error compared
/// is the variance across seeds (both estimators converge to the same image; a heavy tail
/// seen in 12 seeds can only understate the reverse side's). Measured on lavapipe at 32x24,
/// 512 VPLs x 8 frames, seeds 1000-1011, with the plain win-fraction side weights (before the
/// sharpened ones, with which it passes too): reverse 3.62e-2, both 3.78e-3 (9.6x; relative to
/// the mean squared 1.82 and 0.194).
#[test]
#[ignore = "statistical tier: scripts/test.sh --statistical"]
fn both_sides_beat_reverse_only_in_the_halogen_office() {
    with_gpu(|ctx| {
        let scene = scene_file("failure/halogen-office", 32, 24);
        let gpu = GpuScene::upload(ctx, &scene).unwrap();
        let bir = Renderer::<Bir>::new(ctx).unwrap();
        let variance = |strategy: Strategy| {
            let mut standard_weight = 0.0;
            let images: Vec<_> = (0..12)
                .map(|seed| {
                    let settings = BirSettings {
                        vpls: 512,
                        frames: 8,
                        seed: 1000 + seed,
                        strategy,
                        // The sides' own estimators, unclamped as measured above: the
                        // compensated clamp (the default) takes the spikes of both out.
                        clamp: ClampSettings {
                            clamp: VplClamp::Fixed(0.0),
                            compensate: false,
                        },
                        // One direct sample a frame (the G-buffer's hit), as measured: the
                        // test is about the VPLs, and more direct samples only cost time.
                        direct_spp: 1,
                        ..Default::default()
                    };
                    let out = bir.render(ctx, &scene, &gpu, &settings, |_, _| {}).unwrap();
                    assert_eq!(out.nonfinite_estimates, 0);
                    for (name, value) in &out.stats {
                        if name == "final_standard_weight" {
                            standard_weight += value / 12.0;
                        }
                    }
                    out.image
                })
                .collect();
            let means: Vec<f64> = images.iter().map(luminance_mean).collect();
            let (mean, _) = mean_and_stderr(&means);
            let v = irad::image::metrics::variance_across_seeds(&images).unwrap();
            eprintln!(
                "{}: variance across seeds {:.4e} (relative {:.3}), mean {mean:.4}, standard weight {standard_weight:.3}",
                strategy.name(),
                v,
                v / (mean * mean)
            );
            v
        };
        let reverse = variance(Strategy::Reverse);
        let both = variance(Strategy::Both);
        assert!(
            reverse >= 3.0 * both,
            "reverse-only's variance {reverse:.4e} should be at least 3x both's {both:.4e}"
        );
    });
}

/// build_light_cdf walks the lights sequentially in ranges a dispatch, carrying its sums
/// between dispatches (so lavapipe's loop budget never cuts a table of many lights short):
/// the camera-driven table is the same bits whatever the range, and a valid integer CDF.
#[test]
fn the_camera_light_table_is_the_same_whatever_the_split() {
    use irad::gpu::Commands;
    use irad::methods::bir::light_cdf::LightCdf;
    use irad::methods::gbuffer::{GBuffer, PixelSampling, WriteGBuffer};
    with_gpu(|ctx| {
        let scene = scene_file("failure/conference-room", 16, 16);
        let gpu = GpuScene::upload(ctx, &scene).unwrap();
        let gbuffer = GBuffer::new(ctx, &gpu).unwrap();
        let write = WriteGBuffer::new(ctx).unwrap();
        let mut cdf = LightCdf::new(ctx, &gpu).unwrap();
        let table = |cdf: &LightCdf| {
            let mut cmd = Commands::new(ctx).unwrap();
            cmd.pass("gbuffer", |cmd| {
                write.record(cmd, &gpu, &gbuffer, 0, 1, PixelSampling::Centres)
            })
            .unwrap();
            cmd.pass("light cdf", |cmd| cdf.record(cmd, &gpu, &gbuffer, 5, 0.1))
                .unwrap();
            cmd.submit_and_wait().unwrap();
            cdf.table.read().unwrap()
        };
        let whole = table(&cdf);
        assert!(whole.len() >= 8, "{} lights", whole.len());
        for per_dispatch in [1, 3, 7] {
            cdf.lights_per_dispatch = per_dispatch;
            let split = table(&cdf);
            assert!(
                bytemuck::cast_slice::<_, u8>(&split) == bytemuck::cast_slice::<_, u8>(&whole),
                "{per_dispatch} lights a dispatch"
            );
        }
        let mut previous = 0u32;
        let mut total = 0.0f64;
        for e in &whole {
            assert!(e.upper >= previous);
            let p = (e.upper - previous) as f64 / 2147483648.0;
            assert_eq!(e.probability, p as f32);
            assert!(p > 0.0, "the floor keeps every light possible");
            total += p;
            previous = e.upper;
        }
        assert_eq!(previous, 0x80000000);
        assert!((total - 1.0).abs() < 1e-12);
    });
}

/// `reverse_history`: the reverse VPLs' radiance from this batch's and earlier batches'
/// standard VPLs (each set weighted 1 / sets) estimates the same light as from this batch's
/// alone: the reverse side's image mean with 3 sets against 1, paired by seed, within 4
/// standard errors of the difference (or 0.2%; measured -0.00007 ± 0.00004 of 0.184, and, at
/// 3 frames, +0.0020 ± 0.0002 with every set weighted 1).
#[test]
fn earlier_batches_standard_vpls_keep_the_reverse_sides_mean() {
    with_gpu(|ctx| {
        let scene = small_cornell(16);
        let gpu = GpuScene::upload(ctx, &scene).unwrap();
        let bir = Renderer::<Bir>::new(ctx).unwrap();
        let mean = |seed: u32, reverse_history: u32| {
            let settings = BirSettings {
                vpls: 64,
                // 5 frames: the ring of 2 earlier sets is overwritten and read again.
                frames: 5,
                seed,
                strategy: Strategy::Reverse,
                ratio: 0,
                direct_spp: 1,
                reverse_history,
                ..Default::default()
            };
            let out = bir.render(ctx, &scene, &gpu, &settings, |_, _| {}).unwrap();
            assert_eq!(out.nonfinite_estimates, 0);
            luminance_mean(&out.image)
        };
        let pairs: Vec<(f64, f64)> = (0..8)
            .map(|s| (mean(200 + s, 3), mean(200 + s, 1)))
            .collect();
        let differences: Vec<f64> = pairs.iter().map(|(a, b)| a - b).collect();
        let (d, d_se) = mean_and_stderr(&differences);
        let (one, _) = mean_and_stderr(&pairs.iter().map(|p| p.1).collect::<Vec<_>>());
        eprintln!("3 sets - 1 set: {d:+.5} ± {d_se:.5} (mean {one:.5})");
        assert!(
            d.abs() < 4.0 * d_se.max(0.0005 * one),
            "the reverse side with 3 standard VPL sets is {d:+.5} off the one-set mean {one:.5} \
             (± {d_se:.5})"
        );
    });
}
