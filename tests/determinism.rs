//! docs/DESIGN.md "Determinism": the same seed gives bit-identical EXRs on one device;
//! different seeds give different noise around the same mean (within the standard error
//! measured from the images).

use crate::common;

use glam::Vec3;
use irad::gpu::Context;
use irad::image::{exr, Image};
use irad::methods::reference::{Reference, ReferenceSettings};
use irad::methods::Renderer;
use irad::scene::gpu::GpuScene;
use irad::scene::{Light, Scene};

use common::shapes::*;
use common::with_gpu;

/// A closed glossy room lit by an emissive triangle, a spot light and nothing else.
fn room() -> Scene {
    let mut triangles = sphere(2.0, 8, 16, true, 0);
    triangles.push(flat(
        [
            Vec3::new(-0.3, 1.5, -0.3),
            Vec3::new(0.3, 1.5, -0.3),
            Vec3::new(0.0, 1.5, 0.3),
        ],
        1,
    ));
    let mut s = scene(
        "glossy room",
        camera(
            Vec3::new(0.0, 0.0, 1.5),
            Vec3::new(0.0, -0.3, 0.0),
            Vec3::Y,
            70.0,
            24,
        ),
        triangles,
        vec![
            material("wall", 0.4, 0.3, 20.0, 0.0),
            material("lamp", 0.0, 0.0, 1.0, 10.0),
        ],
    );
    s.lights.push(Light::Spot {
        position: Vec3::new(0.5, 1.0, 0.0),
        intensity: Vec3::new(3.0, 2.0, 1.0),
        direction: Vec3::new(-0.2, -1.0, -0.3).normalize(),
        cone_angle: 25.0,
        falloff_angle: 40.0,
    });
    s
}

fn render(ctx: &Context, scene: &Scene, seed: u32) -> Image {
    let gpu = GpuScene::upload(ctx, scene).unwrap();
    let settings = ReferenceSettings {
        spp: 8,
        seed,
        ..Default::default()
    };
    Renderer::<Reference>::new(ctx)
        .unwrap()
        .render(ctx, scene, &gpu, &settings, |_, _| {})
        .unwrap()
        .image
}

#[test]
fn same_seed_same_bits_different_seed_same_mean() {
    with_gpu(|ctx| {
        let scene = room();
        let a = render(ctx, &scene, 7);
        let b = render(ctx, &scene, 7);
        let c = render(ctx, &scene, 8);

        let dir = std::env::temp_dir().join(format!("irad-determinism-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let (pa, pb) = (dir.join("a.exr"), dir.join("b.exr"));
        exr::write(&pa, &a).unwrap();
        exr::write(&pb, &b).unwrap();
        let identical = std::fs::read(&pa).unwrap() == std::fs::read(&pb).unwrap();
        std::fs::remove_dir_all(&dir).ok();
        assert!(identical, "two renders with seed 7 wrote different EXRs");

        // Seeds 7 and 8: the pixel differences (channel sums: the channels of one pixel share
        // their paths) have mean zero; their spread gives the standard error of that mean.
        let diffs: Vec<f64> = a
            .pixels
            .iter()
            .zip(&c.pixels)
            .map(|(p, q)| (0..3).map(|k| p[k] as f64 - q[k] as f64).sum())
            .collect();
        let n = diffs.len() as f64;
        let differing = diffs.iter().filter(|d| **d != 0.0).count();
        assert!(
            differing as f64 > 0.5 * n,
            "seeds 7 and 8 gave (nearly) the same noise"
        );
        let mean = diffs.iter().sum::<f64>() / n;
        let stderr = (diffs.iter().map(|d| d * d).sum::<f64>() / n / n).sqrt();
        eprintln!("mean difference {mean:.5}, standard error {stderr:.5}");
        assert!(
            mean.abs() < 4.0 * stderr,
            "means differ by {mean} (stderr {stderr})"
        );
        assert!(a.mean()[0] > 0.01, "the room should be lit");
    });
}
