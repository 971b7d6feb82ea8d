//! The bound on light power and emitted radiance (src/scene/power.rs): for each kind of light
//! (point, spot, emissive triangle, environment map), a scene at the largest value the loader's
//! message names renders a finite image with no non-finite estimate through each sampler (the
//! path tracer by the power table and by the light BVH, and restir), and a value just above it
//! is refused naming the file, the field and that largest value. And restir reports the
//! reservoirs it drops when their weights overflow (a scene built in code, past the loader).

use crate::common;

use std::path::PathBuf;

use glam::Vec3;
use irad::gpu::Context;
use irad::image::{exr, Image};
use irad::methods::paths::LightSampler;
use irad::methods::reference::{Reference, ReferenceSettings};
use irad::methods::restir::{Combination, Restir, RestirSettings};
use irad::methods::{RenderOutput, Renderer};
use irad::scene::gpu::GpuScene;
use irad::scene::{self, Light, Scene};

use common::shapes::{camera, flat, material, plane_y, scene as scene_of};
use common::with_gpu;

/// A scratch folder under the system temp dir, removed when dropped.
struct Scratch(PathBuf);

impl Scratch {
    fn new(name: &str) -> Scratch {
        let dir = std::env::temp_dir().join(format!("irad-power-{}-{name}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        Scratch(dir)
    }

    fn write(&self, name: &str, text: &str) {
        std::fs::write(self.0.join(name), text).unwrap();
    }
}

impl Drop for Scratch {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

/// A grey plane (4 x 4 at y = 0) seen from above at 16 x 16 pixels, with a weak point light at
/// a corner (so the light BVH has two leaves), and the light under test: `light` is TOML
/// appended to the scene file, `{}` standing for the value.
struct Case {
    name: &'static str,
    /// TOML for the light under test, `{}` for the value.
    toml: &'static str,
    /// The MTL line for the lamp mesh's material, `{}` for the value (emissive triangle).
    lamp_mtl: Option<&'static str>,
    /// (file name in messages, field) the refusal names.
    file: &'static str,
    field: &'static str,
}

const SCENE: &str = "[camera]\nposition = [0.0, 2.0, 3.0]\nlook_at = [0.0, 0.0, 0.0]\n\
    fov_y = 45.0\nresolution = [16, 16]\n\n[[mesh]]\nobj = \"plane.obj\"\n\n\
    [[light]]\nkind = \"point\"\nposition = [1.5, 1.0, 1.5]\nintensity = [1.0, 1.0, 1.0]\n";

impl Case {
    fn write(&self, dir: &Scratch, value: &str) {
        dir.write(
            "plane.obj",
            "mtllib plane.mtl\nusemtl grey\nv -2 0 2\nv 2 0 2\nv 2 0 -2\nv -2 0 -2\nf 1 2 3 4\n",
        );
        dir.write("plane.mtl", "newmtl grey\nKd 0.5 0.5 0.5\n");
        // Facing down at y = 1, area 0.5.
        dir.write(
            "lamp.obj",
            "mtllib lamp.mtl\nusemtl lamp\nv -0.5 1 -0.5\nv 0 1 0.5\nv 0.5 1 -0.5\nf 1 2 3\n",
        );
        dir.write(
            "lamp.mtl",
            &self.lamp_mtl.unwrap_or("Ke 0 0 0").replace("{}", value),
        );
        let mut env = Image::new(8, 4);
        env.pixels.fill([1.0; 3]);
        exr::write(&dir.0.join("env.exr"), &env).unwrap();
        dir.write(
            "scene.toml",
            &format!("{SCENE}\n{}", self.toml.replace("{}", value)),
        );
    }

    fn load(&self, dir: &Scratch, value: &str) -> Result<Scene, scene::SceneError> {
        self.write(dir, value);
        scene::load(&dir.0.join("scene.toml"))
    }
}

const CASES: [Case; 4] = [
    Case {
        name: "point",
        toml: "[[light]]\nkind = \"point\"\nposition = [0.0, 1.0, 0.0]\nintensity = [{}, {}, {}]\n",
        lamp_mtl: None,
        file: "scene.toml",
        field: "light[1].intensity",
    },
    Case {
        name: "spot",
        toml: "[[light]]\nkind = \"spot\"\nposition = [0.0, 1.0, 0.0]\nintensity = [{}, {}, {}]\n\
               direction = [0.0, -1.0, 0.0]\ncone_angle = 30.0\nfalloff_angle = 45.0\n",
        lamp_mtl: None,
        file: "scene.toml",
        field: "light[1].intensity",
    },
    Case {
        name: "triangle",
        toml: "[[mesh]]\nobj = \"lamp.obj\"\n",
        lamp_mtl: Some("newmtl lamp\nKe {} {} {}\n"),
        file: "lamp.mtl",
        field: "material `lamp` Ke",
    },
    Case {
        name: "environment",
        toml: "[environment]\nexr = \"env.exr\"\nscale = {}\n",
        lamp_mtl: None,
        file: "scene.toml",
        field: "environment.scale",
    },
];

/// The largest value a refusal names ("at most V works").
fn largest_named(message: &str) -> f32 {
    let after = message
        .split("at most ")
        .nth(1)
        .unwrap_or_else(|| panic!("no largest value in: {message}"));
    let value = after.split(' ').next().unwrap();
    value
        .parse()
        .unwrap_or_else(|e| panic!("{value:?} in {message}: {e}"))
}

/// The refusal of `value`, checked to name the file and field and a largest value.
fn refusal(case: &Case, dir: &Scratch, value: f32) -> (String, f32) {
    let message = match case.load(dir, &format!("{value:e}")) {
        Ok(_) => panic!("{}: {value:e} loaded, expected a refusal", case.name),
        Err(e) => e.to_string(),
    };
    let path = dir.0.join(case.file).display().to_string();
    assert!(
        message.starts_with(&format!("{path}: {} = ", case.field)),
        "{message}"
    );
    (message.clone(), largest_named(&message))
}

/// The three samplers' renders of `scene`: the path tracer by the light table and by the
/// light BVH, and restir (by the light table).
fn renders(ctx: &Context, scene: &Scene) -> Vec<(&'static str, RenderOutput)> {
    let gpu = GpuScene::upload(ctx, scene).unwrap();
    let reference = Renderer::<Reference>::new(ctx).unwrap();
    let restir = Renderer::<Restir>::new(ctx).unwrap();
    let mut out = Vec::new();
    for (name, light_sampler) in [
        ("reference power", LightSampler::Power),
        ("reference bvh", LightSampler::Bvh),
    ] {
        let settings = ReferenceSettings {
            spp: 2,
            seed: 1,
            light_sampler,
            ..Default::default()
        };
        let o = reference.render(ctx, scene, &gpu, &settings, |_, _| {});
        out.push((name, o.unwrap()));
    }
    let settings = RestirSettings {
        frames: 2,
        seed: 1,
        ..Default::default()
    };
    let o = restir.render(ctx, scene, &gpu, &settings, |_, _| {});
    out.push(("restir", o.unwrap()));
    out
}

/// `case` far past the bound names the largest value; that value renders finite images with
/// every sampler, and one just above it is refused with the same largest value.
fn boundary(case: &Case) {
    let dir = Scratch::new(case.name);
    let (_, largest) = refusal(case, &dir, 3e37);
    let scene = case
        .load(&dir, &format!("{largest:e}"))
        .unwrap_or_else(|e| panic!("{}: the named largest value {largest:e}: {e}", case.name));
    with_gpu(|ctx| {
        for (sampler, out) in renders(ctx, &scene) {
            let at = format!("{} at {largest:e}, {sampler}", case.name);
            assert_eq!(out.nonfinite_estimates, 0, "{at}");
            let pixels = out.image.pixels.iter().flatten();
            assert!(
                pixels.clone().all(|v| v.is_finite()),
                "{at}: image not finite"
            );
            let mean = out.image.mean()[1];
            assert!(mean > 0.0 && mean.is_finite(), "{at}: mean {mean}");
        }
    });
    let above = largest * 1.01;
    let (message, named) = refusal(case, &dir, above);
    assert_eq!(named, largest, "{message}");
}

#[test]
fn a_point_light_at_the_power_bound_renders_and_above_it_is_refused() {
    boundary(&CASES[0]);
}

#[test]
fn a_spot_light_at_the_power_bound_renders_and_above_it_is_refused() {
    boundary(&CASES[1]);
}

#[test]
fn an_emissive_triangle_at_the_power_bound_renders_and_above_it_is_refused() {
    boundary(&CASES[2]);
}

#[test]
fn an_environment_map_at_the_power_bound_renders_and_above_it_is_refused() {
    boundary(&CASES[3]);
}
/// One emissive material in an MTL that two OBJs load (each [[mesh]] parses its own copy) is
/// one field: the largest `Ke` a refusal names counts both OBJs' triangles, so it loads, and
/// one just above it is refused with the same largest value.
#[test]
fn a_material_two_objs_share_is_bounded_once_and_its_named_largest_ke_loads() {
    let dir = Scratch::new("shared-mtl");
    let load = |ke: f32| {
        dir.write(
            "plane.obj",
            "mtllib plane.mtl\nusemtl grey\nv -2 0 2\nv 2 0 2\nv 2 0 -2\nv -2 0 -2\nf 1 2 3 4\n",
        );
        dir.write("plane.mtl", "newmtl grey\nKd 0.5 0.5 0.5\n");
        // Two triangles facing down, area 0.5 each, one per OBJ.
        dir.write(
            "lamp.obj",
            "mtllib lamp.mtl\nusemtl lamp\nv -0.5 1 -0.5\nv 0 1 0.5\nv 0.5 1 -0.5\nf 1 2 3\n",
        );
        dir.write(
            "lamp2.obj",
            "mtllib lamp.mtl\nusemtl lamp\nv -0.5 1.5 -0.5\nv 0 1.5 0.5\nv 0.5 1.5 -0.5\nf 1 2 3\n",
        );
        dir.write(
            "lamp.mtl",
            &format!("newmtl lamp\nKe {ke:e} {ke:e} {ke:e}\n"),
        );
        dir.write(
            "scene.toml",
            &format!("{SCENE}\n[[mesh]]\nobj = \"lamp.obj\"\n\n[[mesh]]\nobj = \"lamp2.obj\"\n"),
        );
        scene::load(&dir.0.join("scene.toml"))
    };
    let refused = |ke: f32| {
        let message = load(ke).map(|_| ()).unwrap_err().to_string();
        let path = dir.0.join("lamp.mtl").display().to_string();
        assert!(
            message.starts_with(&format!("{path}: material `lamp` Ke = ")),
            "{message}"
        );
        (largest_named(&message), message)
    };
    let (largest, message) = refused(3e37);
    // pi Ke (0.5 + 0.5) at most 2^64 with the weak light's 4 pi.
    let expected = (2f64.powi(64) - 4.0 * std::f64::consts::PI) / std::f64::consts::PI;
    assert!(
        largest as f64 <= expected && largest as f64 > 0.99 * expected,
        "{message}"
    );
    load(largest).unwrap_or_else(|e| panic!("the named largest Ke {largest:e}: {e}"));
    let (named, message) = refused(largest * 1.01);
    assert_eq!(named, largest, "{message}");
}

/// A light-field luminaire's atlas texel past the bound on emitted radiance is refused naming
/// the atlas file, the texel and the largest value that works; that value loads.
#[test]
fn a_luminaire_atlas_texel_past_the_radiance_bound_is_refused() {
    let dir = Scratch::new("luminaire");
    dir.write(
        "luminaire.toml",
        "grid = [1, 1]\npitch = [0.01, 0.01]\nbasis = \"bilinear\"\ndelta = 0.05\n\
         image_size = [0.2, 0.2]\natlas = \"images.exr\"\n",
    );
    let atlas = dir.0.join("images.exr");
    let load = |texel: f32| {
        let mut image = Image::new(2, 2);
        image.pixels.fill([1.0; 3]);
        image.pixels[3] = [1.0, texel, 1.0];
        exr::write(&atlas, &image).unwrap();
        irad::scene::luminaire::Luminaire::load(&dir.0.join("luminaire.toml"))
    };
    let refused = |texel: f32| {
        let message = load(texel).map(|_| ()).unwrap_err().to_string();
        assert!(
            message.starts_with(&format!("{}: texel (x 1, y 1) = ", atlas.display())),
            "{message}"
        );
        (largest_named(&message), message)
    };
    let (largest, message) = refused(3e37);
    assert!(
        largest as f64 <= 2f64.powi(64) && largest as f64 > 0.99 * 2f64.powi(64),
        "{message}"
    );
    load(largest).unwrap_or_else(|e| panic!("the named largest texel {largest:e}: {e}"));
    let (named, message) = refused(largest * 1.01);
    assert_eq!(named, largest, "{message}");
}

/// The plane under a point light (and the weak one) at `height` above its centre, built in
/// code past the loader's check.
fn overflowing(height: f32, intensity: f32) -> Scene {
    let mut scene = scene_of(
        "overflow",
        camera(Vec3::new(0.0, 2.0, 3.0), Vec3::ZERO, Vec3::Y, 45.0, 16),
        plane_y(2.0, 0.0, 0),
        vec![material("grey", 0.5, 0.0, 0.0, 0.0)],
    );
    scene.lights = vec![
        Light::Point {
            position: Vec3::new(1.5, 1.0, 1.5),
            intensity: Vec3::ONE,
        },
        Light::Point {
            position: Vec3::new(0.0, height, 0.0),
            intensity: Vec3::splat(intensity),
        },
    ];
    scene
}

/// The plane under a small emissive triangle (area 0.01) of radiance `ke` 1 unit above its
/// centre, facing down, and the weak point light, built in code past the loader's check.
fn small_lamp(ke: f32) -> Scene {
    let mut scene = overflowing(1.0, 0.0);
    scene.lights.truncate(1);
    scene.materials.push(material("lamp", 0.0, 0.0, 0.0, ke));
    scene.triangles.push(flat(
        [
            Vec3::new(-0.1, 1.0, -0.05),
            Vec3::new(0.1, 1.0, -0.05),
            Vec3::new(0.0, 1.0, 0.05),
        ],
        1,
    ));
    scene
}

/// Restir's reservoirs whose weights leave f32's range are dropped and counted: in the
/// candidates' pass (a light of 1e38 at 0.1 above the plane: targets f I cos / d^2 past
/// f32::MAX; through the light BVH its power 4 pi I is infinite, its pmf NaN) and in spatial
/// reuse and temporal reuse, each alone (3e38 and 1e38 at 1 above: finite targets, but
/// confidence M times a target overflows in the MIS weights). And in spatial reuse's
/// one-over-z and biased combinations, where Z p^ overflows while the weight sum stays finite
/// (a small lamp of 3e37 with neighbours within 3 pixels, so most are taken: W about the lamp's
/// area, 0.01, so the sum is about 0.01 Z p^; 27 reservoirs, uncounted before, and none in mis),
/// and likewise in temporal reuse alone (the lamp at 1e38).
#[test]
fn restir_counts_the_reservoirs_it_drops_when_their_weights_overflow() {
    // (name, scene, sampler, temporal, neighbours, radius, combination)
    let cases = [
        (
            "candidates, by power",
            overflowing(0.1, 1e38),
            LightSampler::Power,
            true,
            5,
            30,
            Combination::Mis,
        ),
        (
            "candidates, light BVH",
            overflowing(0.1, 1e38),
            LightSampler::Bvh,
            true,
            5,
            30,
            Combination::Mis,
        ),
        (
            "spatial reuse",
            overflowing(1.0, 3e38),
            LightSampler::Power,
            false,
            5,
            30,
            Combination::Mis,
        ),
        (
            "temporal reuse",
            overflowing(1.0, 1e38),
            LightSampler::Power,
            true,
            0,
            30,
            Combination::Mis,
        ),
        (
            "spatial reuse, one-over-z",
            small_lamp(3e37),
            LightSampler::Power,
            false,
            5,
            3,
            Combination::OneOverZ,
        ),
        (
            "spatial reuse, biased",
            small_lamp(3e37),
            LightSampler::Power,
            false,
            5,
            3,
            Combination::Biased,
        ),
        (
            "temporal reuse, one-over-z",
            small_lamp(1e38),
            LightSampler::Power,
            true,
            0,
            3,
            Combination::OneOverZ,
        ),
        (
            "temporal reuse, biased",
            small_lamp(1e38),
            LightSampler::Power,
            true,
            0,
            3,
            Combination::Biased,
        ),
    ];
    let mut unreported = Vec::new();
    with_gpu(|ctx| {
        let restir = Renderer::<Restir>::new(ctx).unwrap();
        for (name, scene, light_sampler, temporal, neighbours, radius, combination) in &cases {
            let gpu = GpuScene::upload(ctx, scene).unwrap();
            let settings = RestirSettings {
                frames: 2,
                seed: 1,
                light_sampler: *light_sampler,
                temporal: *temporal,
                neighbours: *neighbours,
                radius: *radius,
                combination: *combination,
                ..Default::default()
            };
            let out = restir
                .render(ctx, scene, &gpu, &settings, |_, _| {})
                .unwrap();
            println!("{name}: {} dropped", out.nonfinite_estimates);
            if out.nonfinite_estimates == 0 {
                unreported.push(*name);
            }
            let pixels = out.image.pixels.iter().flatten();
            assert!(pixels.clone().all(|v| v.is_finite()), "{name}");
        }
    });
    assert!(
        unreported.is_empty(),
        "no dropped estimate reported: {unreported:?}"
    );
}
