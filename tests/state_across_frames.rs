//! What a method carries from one frame to the next must hold for the frame that uses it
//! (docs/DESIGN.md "State across frames"). Every method of the registry that renders an
//! environment map, on a map sequence that dims, turns and brightens from frame to frame, keeps
//! the image mean the path tracer gives each map, averaged over the maps its frames show: a
//! method that reused an earlier frame's map (restir's temporal reservoirs weighed by this
//! frame's map kept 0.65 of the light here), sampled by an earlier frame's table, or showed
//! another frame's map (10 frames show maps 0 and 1 three times, 2 and 3 twice, and the maps'
//! brightnesses differ) fails.
//!
//! The scene has direct light only (a plane under the sky, a black sphere casting a shadow, the
//! camera seeing nothing else), so methods that stop after one or two bounces (env, restir,
//! bundles) are judged against the full path tracer.

use crate::common;

use glam::Vec3;
use irad::methods::{Method, Registry, Renderers, Support};
use irad::scene::gpu::GpuScene;
use irad::scene::sky::MovingSun;
use irad::scene::{Environment, Scene};

use common::shapes::*;
use common::{luminance_mean, mean_and_stderr, with_gpu};

/// A map turned about +Y by `quarters` quarter turns (whole columns: u moves by W / 4 each).
fn turned(map: &Environment, quarters: u32) -> Environment {
    let (w, h) = (map.width as usize, map.height as usize);
    let shift = quarters as usize * w / 4;
    let mut texels = map.texels.clone();
    for j in 0..h {
        for i in 0..w {
            texels[j * w + (i + shift) % w] = map.texels[j * w + i];
        }
    }
    Environment {
        texels,
        ..map.clone()
    }
}

fn scaled(map: &Environment, k: f32) -> Environment {
    Environment {
        texels: map.texels.iter().map(|t| *t * k).collect(),
        ..map.clone()
    }
}

/// Four maps, one a frame: a sky with a sun, the same a quarter as bright (it dims), turned a
/// quarter and 0.6 as bright (it turns and brightens), turned a half and twice as bright (it
/// turns and brightens).
fn map_sequence_scene() -> Scene {
    let sky = MovingSun {
        width: 32,
        height: 16,
        frames: 1,
        sun_elevation: 40.0,
        sun_radius: 8.0,
        sun_radiance: Vec3::new(30.0, 28.0, 25.0),
        rising: false,
    }
    .map(0, 1.0);
    let sequence = vec![
        sky.clone(),
        scaled(&sky, 0.25),
        scaled(&turned(&sky, 1), 0.6),
        scaled(&turned(&sky, 2), 2.0),
    ];
    let mut triangles = plane_y(4.0, 0.0, 0);
    triangles.extend(sphere(0.35, 8, 12, false, 1).into_iter().map(|mut t| {
        t.positions = t.positions.map(|p| p + Vec3::new(0.0, 0.6, 0.0));
        t
    }));
    let mut scene = scene(
        "map-sequence",
        camera(Vec3::new(0.0, 3.0, 0.01), Vec3::ZERO, Vec3::Y, 40.0, 16),
        triangles,
        vec![
            material("floor", 0.5, 0.3, 20.0, 0.0),
            material("black", 0.0, 0.0, 1.0, 0.0),
        ],
    );
    scene.environment = Some(sequence[0].clone());
    scene.environment_sequence = sequence;
    scene
}

/// `name` with `count` frames (samples for the path tracer) at `seed`, its defaults otherwise
/// but where they only cost time on a 32 x 16 map (env's cube faces, samples per frame).
fn method(name: &str, count: u32, seed: u32) -> Method {
    let entry = Registry::builtin().get(name).unwrap();
    let cheaper = match name {
        "env" => "spp = 8\nface_resolution = 32",
        _ => "",
    };
    let params: toml::Table = toml::from_str(&format!(
        "{} = {count}\nseed = {seed}\n{cheaper}",
        entry.count_key()
    ))
    .unwrap();
    entry.method_from_toml(&params).unwrap()
}

#[test]
fn every_method_that_renders_a_map_follows_a_sequence_that_dims_turns_and_brightens() {
    with_gpu(|ctx| {
        let scene = map_sequence_scene();
        let gpu = GpuScene::upload(ctx, &scene).unwrap();
        assert_eq!(gpu.environment_frames(), 4);
        let renderers = Renderers::default();
        let mean_of = |m: &Method, scene: &Scene, gpu: &GpuScene| {
            let out = renderers.run(ctx, m, scene, gpu, |_, _| {}).unwrap();
            assert_eq!(out.nonfinite_estimates, 0, "{}", m.name());
            luminance_mean(&out.image)
        };
        // The path tracer on each map alone, 4 seeds of 256 samples.
        let per_map: Vec<(f64, f64)> = scene
            .environment_sequence
            .iter()
            .map(|map| {
                let mut still = scene.clone();
                still.environment = Some(map.clone());
                still.environment_sequence.clear();
                let still_gpu = GpuScene::upload(ctx, &still).unwrap();
                let means: Vec<f64> = (0..4)
                    .map(|s| mean_of(&method("reference", 256, 90 + s), &still, &still_gpu))
                    .collect();
                mean_and_stderr(&means)
            })
            .collect();
        eprintln!("the path tracer's mean per map: {per_map:.4?}");
        // What FRAMES frames show: maps 0 and 1 three times, 2 and 3 twice.
        const FRAMES: u32 = 10;
        let shown = |k: usize| (0..FRAMES).filter(|f| *f as usize % 4 == k).count() as f64;
        let r = (0..4).map(|k| shown(k) * per_map[k].0).sum::<f64>() / FRAMES as f64;
        let r_se = (0..4)
            .map(|k| (shown(k) * per_map[k].1).powi(2))
            .sum::<f64>()
            .sqrt()
            / FRAMES as f64;
        let methods: Vec<&str> = Registry::builtin()
            .entries()
            .iter()
            .filter(|e| {
                let lights = e.lights();
                e.name() != "reference"
                    && !matches!(lights.environment, Support::Declines(_))
                    && !matches!(lights.luminaires, Support::Needs(_))
            })
            .map(|e| e.name())
            .collect();
        // Lightfield renders maps too but needs a luminaire: its map is the driver's direct
        // pass (the path tracer's kernel, no state across frames).
        assert!(
            ["env", "bundles", "restir"]
                .iter()
                .all(|m| methods.contains(m)),
            "{methods:?}"
        );
        let mut failures = vec![];
        for name in methods {
            // Every frame after the first follows a change of map.
            let means: Vec<f64> = (0..16)
                .map(|s| mean_of(&method(name, FRAMES, 10 + s), &scene, &gpu))
                .collect();
            let (m, m_se) = mean_and_stderr(&means);
            let ratio = m / r;
            let se = ratio * ((m_se / m).powi(2) + (r_se / r).powi(2)).sqrt();
            eprintln!("{name}: mean / path tracer {ratio:.4} ± {se:.4}");
            assert!(
                se < 0.015,
                "{name}: too noisy to test (standard error {se:.4})"
            );
            if (ratio - 1.0).abs() > 4.0 * se {
                failures.push(format!("{name} {ratio:.4} ± {se:.4}"));
            }
        }
        assert!(
            failures.is_empty(),
            "off the path tracer's mean by more than 4 standard errors: {failures:?}"
        );
    });
}
