//! The reference path tracer against analytic answers. Each tolerance is 1%; each test also
//! checks that its own Monte Carlo standard error is well below that, so a pass is not luck and
//! a wrong estimator (a missing cos, pi or MIS weight) fails.

use crate::common;

use std::f64::consts::PI;

use glam::Vec3;
use irad::gpu::Context;
use irad::image::Image;
use irad::methods::reference::{Reference, ReferenceSettings};
use irad::methods::Renderer;
use irad::scene::gpu::GpuScene;
use irad::scene::{Environment, Light, Scene};

use common::shapes::*;
use common::with_gpu;

fn render(ctx: &Context, scene: &Scene, spp: u32, seed: u32) -> Image {
    let gpu = GpuScene::upload(ctx, scene).expect("upload");
    let reference = Renderer::<Reference>::new(ctx).expect("kernels");
    let settings = ReferenceSettings {
        spp,
        seed,
        ..Default::default()
    };
    let out = reference
        .render(ctx, scene, &gpu, &settings, |_, _| {})
        .expect("render");
    assert_eq!(out.nonfinite_estimates, 0);
    out.image
}

/// Mean of channel 0 over pixels, and its standard error from the per-pixel spread (the
/// pixels are independent estimates of one value in these scenes).
fn mean_and_stderr(image: &Image, expected_per_pixel: impl Fn(usize) -> f64) -> (f64, f64) {
    let n = image.pixels.len() as f64;
    let ratios: Vec<f64> = image
        .pixels
        .iter()
        .enumerate()
        .map(|(i, p)| p[0] as f64 / expected_per_pixel(i))
        .collect();
    let mean = ratios.iter().sum::<f64>() / n;
    let var = ratios.iter().map(|r| (r - mean).powi(2)).sum::<f64>() / (n - 1.0);
    (mean, (var / n).sqrt())
}

fn assert_within_one_percent(what: &str, ratio: f64, stderr: f64) {
    eprintln!("{what}: rendered / expected = {ratio:.5} (standard error {stderr:.5})");
    assert!(
        stderr < 0.003,
        "{what}: too noisy to test at 1% (stderr {stderr})"
    );
    assert!((ratio - 1.0).abs() < 0.01, "{what}: ratio {ratio}");
}

#[test]
fn furnace_sphere_gives_le_over_one_minus_rho() {
    with_gpu(|ctx| {
        let (rho, le) = (0.6f32, 0.5f32);
        let scene = scene(
            "furnace",
            camera(Vec3::ZERO, Vec3::new(0.0, 0.3, -1.0), Vec3::Y, 90.0, 16),
            sphere(1.0, 12, 24, true, 0),
            vec![material("wall", rho, 0.0, 1.0, le)],
        );
        let image = render(ctx, &scene, 256, 1);
        let expected = (le / (1.0 - rho)) as f64;
        let (ratio, stderr) = mean_and_stderr(&image, |_| expected);
        assert_within_one_percent("furnace", ratio, stderr);
    });
}

/// Pixel-footprint average of (Kd / pi) I cos(theta) / r^2 on the plane y = 0, by a 16 x 16
/// midpoint rule over the pixel through the camera mapping of src/scene/mod.rs.
fn point_light_expected(
    scene: &Scene,
    kd: f64,
    light: Vec3,
    intensity: impl Fn(Vec3) -> f64,
) -> Vec<f64> {
    let cam = &scene.camera;
    let mut out = Vec::new();
    for y in 0..cam.height {
        for x in 0..cam.width {
            let mut sum = 0.0;
            for sy in 0..16 {
                for sx in 0..16 {
                    let (fx, fy) = ((sx as f32 + 0.5) / 16.0, (sy as f32 + 0.5) / 16.0);
                    let d = cam.direction(x as f32 + fx, y as f32 + fy);
                    let hit = cam.position + d * (-cam.position.y / d.y);
                    let to_light = light - hit;
                    let r2 = to_light.length_squared() as f64;
                    let cos = (to_light.y as f64) / r2.sqrt();
                    sum += kd / PI * intensity(-to_light.normalize()) * cos / r2;
                }
            }
            out.push(sum / 256.0);
        }
    }
    out
}

#[test]
fn point_light_over_diffuse_plane_matches_per_pixel() {
    with_gpu(|ctx| {
        let (kd, intensity) = (0.7f32, 3.0f32);
        let light = Vec3::new(0.3, 1.0, -0.2);
        let mut scene = scene(
            "point light over a plane",
            camera(Vec3::new(0.0, 2.0, 1.0), Vec3::ZERO, Vec3::Y, 40.0, 16),
            plane_y(20.0, 0.0, 0),
            vec![material("plane", kd, 0.0, 1.0, 0.0)],
        );
        scene.lights.push(Light::Point {
            position: light,
            intensity: Vec3::splat(intensity),
        });
        let image = render(ctx, &scene, 64, 2);
        let expected = point_light_expected(&scene, kd as f64, light, |_| intensity as f64);
        let mut worst = 0.0f64;
        for (p, e) in image.pixels.iter().zip(&expected) {
            worst = worst.max((p[0] as f64 / e - 1.0).abs());
        }
        eprintln!("point light: worst per-pixel relative error {worst:.5}");
        assert!(worst < 0.01, "worst per-pixel error {worst}");
    });
}

/// pbrt-v4's spot falloff: smoothstep from cos(falloff_angle) to cos(cone_angle).
fn spot_falloff(direction: Vec3, axis: Vec3, cone: f32, falloff: f32) -> f64 {
    let (e0, e1) = (
        falloff.to_radians().cos() as f64,
        cone.to_radians().cos() as f64,
    );
    let x = ((direction.dot(axis) as f64 - e0) / (e1 - e0)).clamp(0.0, 1.0);
    x * x * (3.0 - 2.0 * x)
}

#[test]
fn spot_light_over_diffuse_plane_matches_per_pixel() {
    with_gpu(|ctx| {
        let (kd, intensity) = (0.5f32, 4.0f32);
        let light = Vec3::new(0.0, 1.2, 0.0);
        let axis = Vec3::new(0.2, -1.0, 0.1).normalize();
        let (cone, falloff) = (20.0f32, 35.0f32);
        let mut scene = scene(
            "spot light over a plane",
            camera(Vec3::new(0.0, 2.5, 1.0), Vec3::ZERO, Vec3::Y, 50.0, 16),
            plane_y(20.0, 0.0, 0),
            vec![material("plane", kd, 0.0, 1.0, 0.0)],
        );
        scene.lights.push(Light::Spot {
            position: light,
            intensity: Vec3::splat(intensity),
            direction: axis,
            cone_angle: cone,
            falloff_angle: falloff,
        });
        let image = render(ctx, &scene, 512, 6);
        let expected = point_light_expected(&scene, kd as f64, light, |d| {
            intensity as f64 * spot_falloff(d, axis, cone, falloff)
        });
        // Inside the cone, each pixel within 1%; in the penumbra's steep edge and outside,
        // the footprint average is compared in absolute terms against the peak.
        let peak = expected.iter().cloned().fold(0.0, f64::max);
        let (mut lit, mut worst) = (0, 0.0f64);
        for (p, e) in image.pixels.iter().zip(&expected) {
            let error = (p[0] as f64 - e).abs();
            if *e > 0.5 * peak {
                lit += 1;
                worst = worst.max(error / e);
            } else {
                assert!(
                    error < 0.01 * peak,
                    "penumbra pixel off by {error} (peak {peak})"
                );
            }
        }
        eprintln!("spot light: {lit} lit pixels, worst relative error {worst:.5}");
        assert!(lit > 20, "the spot should light part of the image");
        assert!(worst < 0.01, "worst per-pixel error {worst}");
    });
}

#[test]
fn uniform_environment_over_diffuse_plane_gives_kd_l() {
    with_gpu(|ctx| {
        let (kd, l) = (0.6f32, 1.5f32);
        let mut scene = scene(
            "uniform sky over a plane",
            camera(Vec3::new(0.0, 1.0, 0.5), Vec3::ZERO, Vec3::Y, 40.0, 16),
            plane_y(50.0, 0.0, 0),
            vec![material("plane", kd, 0.0, 1.0, 0.0)],
        );
        scene.environment = Some(uniform_environment(l));
        let image = render(ctx, &scene, 128, 3);
        let (ratio, stderr) = mean_and_stderr(&image, |_| (kd * l) as f64);
        assert_within_one_percent("uniform environment", ratio, stderr);
    });
}

fn sun_environment() -> Environment {
    let (w, h) = (64u32, 32u32);
    let sun = Vec3::new(0.4, 0.8, -0.3).normalize();
    let mut texels = Vec::new();
    for j in 0..h {
        for i in 0..w {
            let phi = 2.0 * std::f32::consts::PI * (i as f32 + 0.5) / w as f32;
            let theta = std::f32::consts::PI * (j as f32 + 0.5) / h as f32;
            let d = Vec3::new(
                theta.sin() * phi.sin(),
                theta.cos(),
                -theta.sin() * phi.cos(),
            );
            let sky = Vec3::new(0.2, 0.3, 0.5) * (0.3 + d.y.max(0.0));
            texels.push(if d.dot(sun) > 0.995 {
                Vec3::splat(400.0)
            } else {
                sky
            });
        }
    }
    Environment {
        width: w,
        height: h,
        texels,
        source: "sun".into(),
    }
}

#[test]
fn sun_environment_over_diffuse_plane_matches_numerical_integral() {
    with_gpu(|ctx| {
        let kd = 0.5f32;
        let env = sun_environment();
        let expected = kd as f64 / PI * irad::sampling::environment::irradiance_up(&env).x;
        let mut scene = scene(
            "sun over a plane",
            camera(Vec3::new(0.0, 1.0, 0.5), Vec3::ZERO, Vec3::Y, 40.0, 16),
            plane_y(50.0, 0.0, 0),
            vec![material("plane", kd, 0.0, 1.0, 0.0)],
        );
        scene.environment = Some(env);
        let image = render(ctx, &scene, 256, 4);
        let (ratio, stderr) = mean_and_stderr(&image, |_| expected);
        assert_within_one_percent("sun environment", ratio, stderr);

        // A bright point light under the plane adds nothing to its top but takes most of the
        // light-selection probability: the environment's samples must stay independent of the
        // number that chose it.
        scene.lights.push(Light::Point {
            position: Vec3::new(0.0, -1.0, 0.0),
            intensity: Vec3::splat(1e4),
        });
        let image = render(ctx, &scene, 512, 4);
        let (ratio, stderr) = mean_and_stderr(&image, |_| expected);
        assert_within_one_percent("sun environment beside a hidden point light", ratio, stderr);
    });
}

/// Directional albedo of the normalized Phong lobe, Ks (n + 2) / (2 pi) times the integral of
/// cos^n(alpha) cos(theta) over the upper hemisphere, by the midpoint rule in the lobe's frame,
/// for a view at `cos_o` from the normal.
fn phong_albedo(ks: f64, n: f64, cos_o: f64) -> f64 {
    let sin_o = (1.0 - cos_o * cos_o).max(0.0).sqrt();
    let normal = glam::DVec3::Y;
    let wo = glam::DVec3::new(sin_o, cos_o, 0.0);
    let r = 2.0 * wo.dot(normal) * normal - wo;
    let (tu, tb) = r.any_orthonormal_pair();
    // 500 x 128 cells: within 1.3e-5 of 2000 x 256 over the plate's view angles (cos 0.62 to
    // 0.93), a thousandth of the 1% tested, at a sixteenth of the unoptimized test's 20 s.
    let (na, np) = (500, 128);
    let mut sum = 0.0;
    for ia in 0..na {
        let alpha = (ia as f64 + 0.5) / na as f64 * (PI / 2.0);
        let weight = alpha.cos().powf(n) * alpha.sin();
        for ip in 0..np {
            let phi = (ip as f64 + 0.5) / np as f64 * 2.0 * PI;
            let wi = alpha.cos() * r + alpha.sin() * (phi.cos() * tu + phi.sin() * tb);
            sum += weight * wi.y.max(0.0);
        }
    }
    let integral = sum * (PI / 2.0 / na as f64) * (2.0 * PI / np as f64);
    ks * (n + 2.0) / (2.0 * PI) * integral
}

#[test]
fn phong_plate_under_uniform_environment_gives_its_albedo() {
    with_gpu(|ctx| {
        let (kd, ks, n, l) = (0.1f32, 0.6f32, 30.0f32, 1.0f32);
        let position = Vec3::new(0.0, 1.0, 0.6);
        let mut scene = scene(
            "phong plate",
            camera(position, Vec3::ZERO, Vec3::Y, 30.0, 16),
            plane_y(50.0, 0.0, 0),
            vec![material("plate", kd, ks, n, 0.0)],
        );
        scene.environment = Some(uniform_environment(l));
        // The view angle of the plate changes across the image: expected value per pixel at
        // its centre ray (the albedo is smooth in the angle).
        let cam = scene.camera.clone();
        let expected: Vec<f64> = (0..cam.height * cam.width)
            .map(|i| {
                let (x, y) = (i % cam.width, i / cam.width);
                let d = cam.direction(x as f32 + 0.5, y as f32 + 0.5);
                let cos_o = -d.y as f64;
                (kd as f64 + phong_albedo(ks as f64, n as f64, cos_o)) * l as f64
            })
            .collect();
        let image = render(ctx, &scene, 128, 5);
        let (ratio, stderr) = mean_and_stderr(&image, |i| expected[i]);
        assert_within_one_percent("phong plate", ratio, stderr);
    });
}

/// Veach's multiple importance sampling scene (Veach 1997 Fig. 9.2; Lu 14 Fig. 5.1 left): four
/// glossy plates, Phong exponents 10 to 10,000 from front to back, each tilted to reflect the
/// camera's rays toward a row of four spherical area lights whose radii run from 0.05 to 0.8
/// (radiance falling as 1/r^2, so equal power): per pixel the better strategy changes from light
/// to BSDF sampling.
fn veach_plates(size: u32) -> Scene {
    let camera = camera(
        Vec3::new(0.0, 2.0, 5.0),
        Vec3::new(0.0, 0.4, 0.0),
        Vec3::Y,
        30.0,
        size,
    );
    let mut materials = vec![];
    let mut triangles = vec![];
    let lights_centre = Vec3::new(0.0, 2.5, -2.0);
    for (k, &ns) in [10.0f32, 100.0, 1000.0, 10000.0].iter().enumerate() {
        materials.push(material(&format!("plate {ns}"), 0.05, 0.9, ns, 0.0));
        let c = Vec3::new(0.0, 0.15 * k as f32, 1.0 - 0.6 * k as f32);
        let n = ((camera.position - c).normalize() + (lights_centre - c).normalize()).normalize();
        let u = Vec3::X;
        let v = n.cross(u);
        let p = |a: f32, b: f32| c + a * 2.5 * u + b * 0.4 * v;
        let m = materials.len() as u32 - 1;
        triangles.push(flat([p(-1.0, -1.0), p(1.0, -1.0), p(1.0, 1.0)], m));
        triangles.push(flat([p(-1.0, -1.0), p(1.0, 1.0), p(-1.0, 1.0)], m));
    }
    for (&x, &r) in [-2.1f32, -1.2, 0.0, 1.7]
        .iter()
        .zip(&[0.05f32, 0.15, 0.4, 0.8])
    {
        materials.push(material("light", 0.0, 0.0, 0.0, 2.0 * (0.1 / r).powi(2)));
        let m = materials.len() as u32 - 1;
        let centre = Vec3::new(x, 2.5, -2.0);
        triangles.extend(sphere(r, 8, 16, false, m).into_iter().map(|mut t| {
            t.positions = t.positions.map(|q| q + centre);
            t
        }));
    }
    scene("veach-plates", camera, triangles, materials)
}

fn direct_light(
    ctx: &Context,
    scene: &Scene,
    gpu: &GpuScene,
    spp: u32,
    seed: u32,
    alpha: Option<u32>,
) -> Image {
    let settings = ReferenceSettings {
        spp,
        seed,
        max_depth: 1,
        alpha_frames: alpha,
        ..Default::default()
    };
    let out = Renderer::<Reference>::new(ctx)
        .unwrap()
        .render(ctx, scene, gpu, &settings, |_, _| {})
        .unwrap();
    assert_eq!(out.nonfinite_estimates, 0);
    if alpha.is_some() {
        assert!(out.stats.iter().any(|(k, _)| k == "mean_alpha"));
        assert_eq!(out.maps[0].0, "alpha");
    }
    out.image
}

fn luminance(p: [f32; 3]) -> f64 {
    0.2126 * p[0] as f64 + 0.7152 * p[1] as f64 + 0.0722 * p[2] as f64
}

/// Lu 14 Chapter 5 in the reference's direct light (`--max-depth 1 --alpha-frames M`), on
/// Veach's plates under four area lights: the image mean over 16 seeds within 1% of the
/// power-heuristic reference's (unbiased whatever alpha), and the per-pixel variance over the
/// 16 seeds, averaged over the pixels, below that of the balance heuristic's half and half
/// (the same kernel with every frame an estimation frame) at the same 128 frames, alpha
/// estimated over the first 32 (the thesis:
/// 26% lower on its glossy scene under five area lights, without visibility).
#[test]
#[ignore = "statistical tier: scripts/test.sh --statistical"]
fn alpha_direct_light_is_unbiased_and_lowers_the_variance() {
    with_gpu(|ctx| {
        let scene = veach_plates(48);
        let gpu = GpuScene::upload(ctx, &scene).unwrap();
        let reference = direct_light(ctx, &scene, &gpu, 4096, 91, None);
        let r: f64 = reference.pixels.iter().map(|&p| luminance(p)).sum::<f64>();
        let run = |m: u32| -> (Vec<f64>, f64) {
            let images: Vec<Image> = (0..16)
                .map(|seed| direct_light(ctx, &scene, &gpu, 128, 300 + seed, Some(m)))
                .collect();
            let means = images
                .iter()
                .map(|im| im.pixels.iter().map(|&p| luminance(p)).sum::<f64>() / r)
                .collect();
            let pixels = images[0].pixels.len();
            let mut variance = 0.0;
            for k in 0..pixels {
                let y: Vec<f64> = images.iter().map(|im| luminance(im.pixels[k])).collect();
                let mean = y.iter().sum::<f64>() / y.len() as f64;
                variance += y.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / 15.0;
            }
            (means, variance / pixels as f64)
        };
        let (alpha_means, alpha_variance) = run(32);
        let (balance_means, balance_variance) = run(128);
        for (name, means) in [("alpha", &alpha_means), ("balance", &balance_means)] {
            let n = means.len() as f64;
            let mean = means.iter().sum::<f64>() / n;
            let stderr =
                (means.iter().map(|m| (m - mean).powi(2)).sum::<f64>() / (n - 1.0) / n).sqrt();
            eprintln!("{name}: mean / power-heuristic reference {mean:.4} ± {stderr:.4}");
            assert!(stderr < 0.004, "{name}: standard error {stderr}");
            assert!((mean - 1.0).abs() < 0.01, "{name}: mean {mean:.4}");
        }
        eprintln!(
            "mean per-pixel variance: balance {balance_variance:.4e}, alpha {alpha_variance:.4e} ({:+.1}%)",
            100.0 * (alpha_variance / balance_variance - 1.0)
        );
        assert!(alpha_variance < 0.9 * balance_variance);
    });
}

/// The kernel specialized to a scene's features (scene.glsl's SCENE_HAS_* constants) compiles
/// out only code the scene never runs: its image has the bits of the general kernel's.
#[test]
fn kernels_specialized_to_a_scene_give_the_general_kernels_bits() {
    use irad::scene::gpu::SceneFeatures;
    let cases = [
        // (scene, its features: environment, delta lights, glossy, textures)
        ("cornell-box", [false, false, false, false]),
        ("failure/corner-light", [false, true, false, false]),
        ("spot-light", [false, true, true, false]),
        ("failure/glossy-cornell", [false, true, true, false]),
        ("glossy-env", [true, false, true, false]),
        ("textured-cornell", [false, false, false, true]),
    ];
    with_gpu(|ctx| {
        let reference = Renderer::<Reference>::new(ctx).expect("kernels");
        let settings = ReferenceSettings {
            spp: 4,
            seed: 3,
            ..Default::default()
        };
        for (name, [environment, delta_lights, glossy, textures]) in cases {
            let scene = common::scene_file(name, 24, 24);
            let mut gpu = GpuScene::upload(ctx, &scene).expect("upload");
            let features = SceneFeatures {
                environment,
                delta_lights,
                glossy,
                textures,
            };
            assert_eq!(gpu.features, features, "{name}");
            let specialized = reference
                .render(ctx, &scene, &gpu, &settings, |_, _| {})
                .unwrap();
            gpu.features = SceneFeatures::ALL;
            let general = reference
                .render(ctx, &scene, &gpu, &settings, |_, _| {})
                .unwrap();
            assert!(
                specialized.image.pixels.iter().any(|p| p[0] > 0.0),
                "{name}: a black image tests nothing"
            );
            assert_eq!(specialized.image.pixels, general.image.pixels, "{name}");
        }
    });
}

/// A scene at the loader's coordinate limit (1e8, src/scene/obj.rs MAX_COORDINATE) renders as
/// the same scene at unit scale does: radiance does not change when lengths scale by s and the
/// point light's intensity by s^2 (beyond it f32 rays and the BVH fail: at 1e10 the image came
/// out black).
#[test]
fn a_scene_at_the_coordinate_limit_renders_as_at_unit_scale() {
    with_gpu(|ctx| {
        let mean_at = |scale: f32| {
            let mut scene = scene(
                "far",
                camera(
                    Vec3::new(0.0, 0.6, 0.9) * scale,
                    Vec3::ZERO,
                    Vec3::Y,
                    40.0,
                    16,
                ),
                plane_y(scale, 0.0, 0),
                vec![material("grey", 0.5, 0.0, 0.0, 0.0)],
            );
            scene.lights.push(Light::Point {
                position: Vec3::new(0.0, 0.5, 0.0) * scale,
                intensity: Vec3::splat(scale * scale),
            });
            let image = render(ctx, &scene, 16, 5);
            image.pixels.iter().map(|p| p[0] as f64).sum::<f64>() / image.pixels.len() as f64
        };
        let (unit, far) = (mean_at(1.0), mean_at(1e8));
        eprintln!("image mean at unit scale {unit:.6}, at 1e8 {far:.6}");
        assert!(unit > 0.01, "{unit}");
        assert!((far / unit - 1.0).abs() < 0.01, "{far} against {unit}");
    });
}
