//! Instant radiosity (issue 4 item 5): the walk's survivor counts, and the estimator against
//! the reference.

mod common;

use glam::Vec3;
use irad::gpu::{Commands, Context};
use irad::image::Image;
use irad::methods::ir::schedule::{Absorption, Schedule};
use irad::methods::ir::walk::{TraceVpls, VplBuffers, VPL_NONE};
use irad::methods::ir::{InstantRadiosity, IrSettings};
use irad::methods::reference::{Reference, ReferenceSettings};
use irad::scene::gpu::GpuScene;
use irad::scene::{Light, Scene};

use common::shapes::*;
use common::with_gpu;

/// A closed sphere of albedo 0.5 everywhere, lit by a point light inside: every walk stays
/// inside, so exactly floor(0.5^j N) paths reach vertex j.
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
        walk.record(&mut cmd, &gpu, &buffers, 3).unwrap();
        cmd.submit_and_wait().unwrap();
        let vpls = buffers.vpls.read().unwrap();
        for (j, level) in schedule.levels.iter().enumerate() {
            let (count, offset) = (level[0] as usize, level[1] as usize);
            let expected = (0.5f64.powi(j as i32) * n as f64).floor() as usize;
            assert_eq!(count, expected, "schedule at vertex {j}");
            let alive = vpls[offset..offset + count]
                .iter()
                .filter(|v| v.kind() != VPL_NONE)
                .count();
            assert_eq!(alive, expected, "VPLs at vertex {j}");
        }
    });
}

fn small_cornell() -> Scene {
    let mut scene = irad::scene::default_scene();
    scene.camera.width = 64;
    scene.camera.height = 64;
    scene
}

fn reference(ctx: &Context, scene: &Scene, spp: u32) -> Image {
    let gpu = GpuScene::upload(ctx, scene).unwrap();
    let settings = ReferenceSettings {
        spp,
        seed: 1234,
        ..Default::default()
    };
    Reference::new(ctx)
        .unwrap()
        .render(ctx, &gpu, &settings, |_, _| {})
        .unwrap()
        .image
}

fn ir(ctx: &Context, scene: &Scene, settings: &IrSettings) -> Image {
    let gpu = GpuScene::upload(ctx, scene).unwrap();
    let out = InstantRadiosity::new(ctx)
        .unwrap()
        .render(ctx, scene, &gpu, settings, |_, _| {})
        .unwrap();
    assert_eq!(out.nonfinite_estimates, 0);
    out.image
}

fn luminance_mean(image: &Image) -> f64 {
    let m = image.mean();
    0.2126 * m[0] + 0.7152 * m[1] + 0.0722 * m[2]
}

/// (a) Unclamped ir converges to the reference: the mean over 16 seeds is within 1%.
#[test]
fn unclamped_ir_mean_matches_the_reference() {
    with_gpu(|ctx| {
        let scene = small_cornell();
        let r = luminance_mean(&reference(ctx, &scene, 512));
        let means: Vec<f64> = (0..16)
            .map(|seed| {
                let settings = IrSettings {
                    paths: 256,
                    frames: 4,
                    seed,
                    ..Default::default()
                };
                luminance_mean(&ir(ctx, &scene, &settings))
            })
            .collect();
        let n = means.len() as f64;
        let mean = means.iter().sum::<f64>() / n;
        let stderr = (means.iter().map(|m| (m - mean).powi(2)).sum::<f64>() / (n - 1.0) / n).sqrt();
        eprintln!(
            "ir mean / reference mean = {:.5} (standard error {:.5})",
            mean / r,
            stderr / r
        );
        assert!(stderr / r < 0.004, "too noisy to test at 1%");
        assert!((mean / r - 1.0).abs() < 0.01, "ir mean {mean}, reference {r}");
    });
}
