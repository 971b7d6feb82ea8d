//! Albedo textures (docs/DESIGN.md "Textures") against closed forms: a textured plane under a
//! point light and under a uniform sky, per pixel, for every method that renders the light; a
//! furnace whose albedo is a texture, for the path tracer; and indirect light off a textured
//! floor, where a VPL, a reverse VPL, a bundle vertex and a path vertex must each carry the
//! texture's albedo.

use crate::common;

use std::f64::consts::PI;

use glam::{Vec2, Vec3};
use irad::gpu::Context;
use irad::image::Image;
use irad::render::{self, RenderJob};
use irad::scene::{Light, Scene, Texture, Wrap};

use common::shapes::*;
use common::{with_gpu, Scratch};

/// A width x height texture of grey levels (exact in half precision).
fn grey_texture(width: u32, height: u32, levels: &[f32], wrap: Wrap) -> Texture {
    assert_eq!(levels.len(), (width * height) as usize);
    Texture {
        width,
        height,
        texels: levels.iter().map(|&v| Vec3::splat(v)).collect(),
        wrap: [wrap; 2],
        source: "test texture".into(),
    }
}

/// The plane y = 0 (|x|, |z| <= half) with u = (x + half) / (2 half) * repeats and v = (half
/// - z) / (2 half) * repeats.
fn textured_plane(half: f32, repeats: f32, material: u32) -> Vec<irad::scene::Triangle> {
    let mut tris = plane_y(half, 0.0, material);
    for t in &mut tris {
        t.uvs = t
            .positions
            .map(|p| Vec2::new(p.x + half, half - p.z) / (2.0 * half) * repeats);
    }
    tris
}

/// The plane y = 0 (|x|, |z| <= half) as n x n quads of two triangles each, counter-clockwise
/// seen from +Y, where triangle k's uv is a common affine map of the point plus an offset of
/// its own: a kernel that reads another triangle's coordinates (a wrong stored index, the
/// scene's order for the BVH's) reads a shifted texture. The map takes u over [-0.56, 1.16]
/// and v over [-0.22, 1.12] in view, past both edges of the texture.
struct GridPlane {
    half: f32,
    n: u32,
}

impl GridPlane {
    fn offset(k: u32) -> Vec2 {
        Vec2::new(0.13 * (k % 7) as f32, 0.07 * (k % 3) as f32)
    }

    fn base(&self, p: Vec3) -> Vec2 {
        let t = |c: f32| (c + self.half) / (2.0 * self.half);
        Vec2::new(t(p.x) * 3.0 - 1.2, t(-p.z) * 3.2 - 1.5)
    }

    /// Quad (i, j) at x0 + i d, z0 + j d; triangle 2 (j n + i) below its diagonal (the
    /// local z under the local x), 2 (j n + i) + 1 above.
    fn triangle_of(&self, p: Vec3) -> u32 {
        let d = 2.0 * self.half / self.n as f32;
        let fx = (p.x + self.half) / d;
        let fz = (p.z + self.half) / d;
        let (i, j) = (
            (fx.floor() as u32).min(self.n - 1),
            (fz.floor() as u32).min(self.n - 1),
        );
        let above = fz - j as f32 > fx - i as f32;
        2 * (j * self.n + i) + u32::from(above)
    }

    fn uv(&self, p: Vec3) -> Vec2 {
        self.base(p) + Self::offset(self.triangle_of(p))
    }

    fn triangles(&self, material: u32) -> Vec<irad::scene::Triangle> {
        let d = 2.0 * self.half / self.n as f32;
        let mut tris = Vec::new();
        for j in 0..self.n {
            for i in 0..self.n {
                let (x0, z0) = (-self.half + i as f32 * d, -self.half + j as f32 * d);
                let c = |a: f32, b: f32| Vec3::new(x0 + a * d, 0.0, z0 + b * d);
                let below = [c(0.0, 0.0), c(1.0, 1.0), c(1.0, 0.0)];
                let above = [c(0.0, 0.0), c(0.0, 1.0), c(1.0, 1.0)];
                for (half, corners) in [below, above].into_iter().enumerate() {
                    let k = 2 * (j * self.n + i) + half as u32;
                    let mut t = flat(corners, material);
                    t.uvs = corners.map(|p| self.base(p) + Self::offset(k));
                    tris.push(t);
                }
            }
        }
        tris
    }
}

/// The uv of the plane's point p (textured_plane's mapping).
fn plane_uv(p: Vec3, half: f32, repeats: f32) -> Vec2 {
    Vec2::new(p.x + half, half - p.z) / (2.0 * half) * repeats
}

fn render_method(ctx: &Context, scene: &Scene, method: &str, params: &str, dir: &Scratch) -> Image {
    let method = irad::methods::Registry::builtin()
        .from_params(method, &toml::from_str(params).unwrap())
        .unwrap();
    let job = RenderJob {
        scene,
        method,
        out: dir.0.join(format!("{}", dir.0.read_dir().unwrap().count())),
        exposure: 0.0,
        reference: None,
        frame: None,
    };
    let report = render::render(ctx, &job, |_, _| {}).unwrap();
    assert!(
        report.record.warnings.is_empty(),
        "{:?}",
        report.record.warnings
    );
    report.image
}

/// Pixel-footprint averages of f(hit point on y = 0), by a 8 x 8 midpoint rule through the
/// camera mapping.
fn plane_expected(scene: &Scene, f: impl Fn(Vec3) -> f64) -> Vec<f64> {
    let cam = &scene.camera;
    let mut out = Vec::new();
    for y in 0..cam.height {
        for x in 0..cam.width {
            let mut sum = 0.0;
            for sy in 0..8 {
                for sx in 0..8 {
                    let (fx, fy) = ((sx as f32 + 0.5) / 8.0, (sy as f32 + 0.5) / 8.0);
                    let d = cam.direction(x as f32 + fx, y as f32 + fy);
                    sum += f(cam.position + d * (-cam.position.y / d.y));
                }
            }
            out.push(sum / 64.0);
        }
    }
    out
}

/// Rendered over expected, averaged over the pixels whose expected albedo is below the median
/// and over those above it, with each group's standard error: a method that ignores the
/// texture is off in opposite directions in the two groups.
fn group_ratios(image: &Image, expected: &[f64], albedo: &[f64]) -> [(f64, f64); 2] {
    let mut sorted = albedo.to_vec();
    sorted.sort_by(f64::total_cmp);
    let median = sorted[sorted.len() / 2];
    [false, true].map(|bright| {
        let ratios: Vec<f64> = image
            .pixels
            .iter()
            .zip(expected)
            .zip(albedo)
            .filter(|(_, a)| (**a >= median) == bright)
            .map(|((p, e), _)| p[0] as f64 / e)
            .collect();
        common::mean_and_stderr(&ratios)
    })
}

fn check_groups(what: &str, groups: [(f64, f64); 2], tolerance: f64) {
    for ((ratio, stderr), group) in groups.into_iter().zip(["dark", "bright"]) {
        eprintln!("{what}, {group} texels: rendered / expected = {ratio:.4} (stderr {stderr:.4})");
        assert!(
            stderr < tolerance / 3.0,
            "{what}: too noisy to test at {tolerance}"
        );
        assert!(
            (ratio - 1.0).abs() < tolerance,
            "{what}, {group} texels: rendered / expected = {ratio}"
        );
    }
}

/// 4 x 4 texels of albedo 0.125 to 1 over the view, repeated twice across the plane.
fn plane_texture() -> Texture {
    let levels = [
        1.0, 0.25, 0.75, 0.125, 0.5, 0.875, 0.25, 1.0, 0.125, 0.625, 1.0, 0.375, 0.75, 0.25, 0.5,
        0.875,
    ];
    grey_texture(4, 4, &levels, Wrap::Repeat)
}

#[test]
fn a_textured_plane_under_a_point_light_matches_its_closed_form_per_pixel() {
    let dir = Scratch::new("textures", "point");
    let (kd, intensity) = (0.8f32, 3.0f32);
    let light = Vec3::new(0.3, 1.0, -0.2);
    let plane = GridPlane { half: 2.0, n: 4 };
    let mut scene = scene(
        "textured plane, point light",
        camera(Vec3::new(0.0, 2.0, 0.5), Vec3::ZERO, Vec3::Z, 60.0, 16),
        plane.triangles(0),
        vec![material("plane", kd, 0.0, 1.0, 0.0)],
    );
    scene.materials[0].albedo_texture = Some(0);
    // 5 x 3 texels, mirrored across and clamped down (a wrong row stride, axis or wrap shows).
    let levels = [
        1.0, 0.25, 0.75, 0.125, 0.5, 0.875, 0.25, 1.0, 0.125, 0.625, 0.375, 0.75, 0.25, 0.5, 0.875,
    ];
    let mut texture = grey_texture(5, 3, &levels, Wrap::Mirror);
    texture.wrap[1] = Wrap::Clamp;
    scene.textures.push(texture);
    scene.lights.push(Light::Point {
        position: light,
        intensity: Vec3::splat(intensity),
    });
    let texture = &scene.textures[0];
    let albedo = |p: Vec3| kd as f64 * texture.sample(plane.uv(p)).x as f64;
    let expected = plane_expected(&scene, |p| {
        let to_light = light - p;
        let r2 = to_light.length_squared() as f64;
        albedo(p) / PI * intensity as f64 * (to_light.y as f64 / r2.sqrt()) / r2
    });
    let albedos = plane_expected(&scene, albedo);
    with_gpu(|ctx| {
        for (method, params) in [
            ("reference", "spp = 64"),
            ("ir", "frames = 16\nvpls = 16"),
            ("bir", "frames = 16"),
            ("bundles", "frames = 16\niterations = 4"),
            ("restir", "frames = 16"),
        ] {
            let image = render_method(ctx, &scene, method, params, &dir);
            check_groups(
                &format!("{method}, point light"),
                group_ratios(&image, &expected, &albedos),
                0.01,
            );
        }
    });
}

#[test]
fn a_textured_plane_under_a_uniform_sky_matches_its_closed_form_per_pixel() {
    let dir = Scratch::new("textures", "sky");
    let (half, repeats, kd, sky) = (2.0f32, 2.0f32, 0.8f32, 0.5f32);
    let mut scene = scene(
        "textured plane, uniform sky",
        camera(Vec3::new(0.0, 2.0, 0.5), Vec3::ZERO, Vec3::Z, 60.0, 16),
        textured_plane(half, repeats, 0),
        vec![material("plane", kd, 0.0, 1.0, 0.0)],
    );
    scene.materials[0].albedo_texture = Some(0);
    scene.textures.push(plane_texture());
    scene.environment = Some(uniform_environment(sky));
    let texture = &scene.textures[0];
    let albedo = |p: Vec3| kd as f64 * texture.sample(plane_uv(p, half, repeats)).x as f64;
    // The plane sees the whole upper hemisphere of sky: irradiance pi L, radiance albedo L.
    let expected = plane_expected(&scene, |p| albedo(p) * sky as f64);
    let albedos = plane_expected(&scene, albedo);
    with_gpu(|ctx| {
        for (method, params) in [
            ("reference", "spp = 64"),
            ("env", "frames = 16"),
            ("bundles", "frames = 16\niterations = 4"),
            ("restir", "frames = 16"),
        ] {
            let image = render_method(ctx, &scene, method, params, &dir);
            check_groups(
                &format!("{method}, sky"),
                group_ratios(&image, &expected, &albedos),
                0.02,
            );
        }
    });
}

/// Inside a sphere that emits Le everywhere and reflects with albedo rho(x), every point sees
/// the same irradiance (a sphere's form factor to an area element does not depend on where it
/// is seen from), so L(x) = Le + rho(x) Le / (1 - rho_mean), rho_mean the area average of rho.
/// The texture varies with longitude alone, so rho_mean is the mean of its texels.
#[test]
fn a_furnace_with_a_textured_albedo_gives_its_closed_form() {
    let le = 0.5f32;
    let levels = [0.25, 0.75, 0.5, 0.875, 0.125, 0.625, 0.375, 0.5];
    let rho_mean = levels.iter().sum::<f32>() as f64 / levels.len() as f64;
    let (rings, segments) = (12, 24);
    let mut triangles = sphere(1.0, rings, segments, true, 0);
    // u = longitude / 2 pi (sphere()'s phi, from the corner's x and z), unwrapped per triangle.
    for t in &mut triangles {
        let pole = t.positions.map(|p| p.x.hypot(p.z) < 1e-6);
        let mut u = t.positions.map(|p| {
            let phi = p.z.atan2(p.x);
            (if phi < 0.0 {
                phi + 2.0 * std::f32::consts::PI
            } else {
                phi
            }) / (2.0 * std::f32::consts::PI)
        });
        // A triangle across phi = 0 unwraps; a pole's corner takes the mean longitude of the
        // other two.
        let max = (0..3)
            .filter(|&c| !pole[c])
            .map(|c| u[c])
            .fold(0.0, f32::max);
        for c in 0..3 {
            if !pole[c] && max - u[c] > 0.5 {
                u[c] += 1.0;
            }
        }
        for c in 0..3 {
            if pole[c] {
                u[c] = (0..3).filter(|&k| k != c).map(|k| u[k]).sum::<f32>() / 2.0;
            }
        }
        t.uvs = u.map(|u| Vec2::new(u, 0.5));
    }
    let mut scene = scene(
        "textured furnace",
        camera(Vec3::ZERO, Vec3::new(0.0, 0.3, -1.0), Vec3::Y, 90.0, 16),
        triangles,
        vec![material("wall", 1.0, 0.0, 1.0, le)],
    );
    scene.materials[0].albedo_texture = Some(0);
    scene
        .textures
        .push(grey_texture(8, 1, &levels, Wrap::Repeat));
    let texture = scene.textures[0].clone();
    let dir = Scratch::new("textures", "furnace");
    with_gpu(|ctx| {
        let image = render_method(ctx, &scene, "reference", "spp = 256\nseed = 1", &dir);
        // Each pixel's expected value from its centre's longitude (the camera is at the centre).
        let cam = &scene.camera;
        let rhos: Vec<f64> = (0..cam.height)
            .flat_map(|y| (0..cam.width).map(move |x| (x, y)))
            .map(|(x, y)| {
                let d = cam.direction(x as f32 + 0.5, y as f32 + 0.5);
                let phi = d.z.atan2(d.x);
                let u = phi / (2.0 * std::f32::consts::PI);
                texture.sample(Vec2::new(u, 0.5)).x as f64
            })
            .collect();
        let expected: Vec<f64> = rhos
            .iter()
            .map(|rho| le as f64 * (1.0 + rho / (1.0 - rho_mean)))
            .collect();
        // Pixels of low and of high albedo apart: the first hit's texel decides which, the
        // bounces' mean albedo the level of both.
        check_groups(
            "textured furnace",
            group_ratios(&image, &expected, &rhos),
            0.015,
        );
        // Had the walls' albedo been Kd alone (1), the furnace would not converge; had it been
        // the pixel's texel alone at every bounce, the level would be Le / (1 - rho(x)).
    });
}

/// lightfield renders luminaires alone, which have no closed form here: the headlight wall
/// rendered with every material textured (a checker of 0.25 and 1 projected on x and y + z)
/// and without, with the same seed, differ per pixel by the texture's value at the pixel's
/// hits, so each pixel's ratio lies in [0.25, 1], and both ends occur.
#[test]
fn lightfield_shades_with_the_textured_albedo() {
    let dir = Scratch::new("textures", "lightfield");
    let plain = common::scene_file("failure/headlight-wall", 48, 32);
    let mut textured = plain.clone();
    // Quadrants of 0.25 and 1 (constant but for a texel's width at their edges).
    let quadrants: Vec<f32> = (0..256)
        .map(|i| {
            if (i % 16 < 8) == (i / 16 < 8) {
                0.25
            } else {
                1.0
            }
        })
        .collect();
    textured
        .textures
        .push(grey_texture(16, 16, &quadrants, Wrap::Repeat));
    for m in &mut textured.materials {
        m.albedo_texture = Some(0);
    }
    for t in &mut textured.triangles {
        t.uvs = t.positions.map(|p| Vec2::new(p.x, p.y + p.z) * 0.2);
    }
    with_gpu(|ctx| {
        let params = "frames = 4\nseed = 3";
        let a = render_method(ctx, &textured, "lightfield", params, &dir);
        let b = render_method(ctx, &plain, "lightfield", params, &dir);
        let ratios: Vec<f64> = a
            .pixels
            .iter()
            .zip(&b.pixels)
            .filter(|(_, q)| q[0] > 1e-4)
            .map(|(p, q)| p[0] as f64 / q[0] as f64)
            .collect();
        let (low, high) = ratios
            .iter()
            .fold((f64::MAX, f64::MIN), |(l, h), r| (l.min(*r), h.max(*r)));
        eprintln!(
            "lightfield: {} lit pixels, textured / plain in [{low:.4}, {high:.4}]",
            ratios.len()
        );
        assert!(ratios.len() > 50, "too few lit pixels");
        assert!(low > 0.25 - 1e-3 && high < 1.0 + 1e-3, "[{low}, {high}]");
        assert!(
            low < 0.3 && high > 0.95,
            "the texture's range is not seen: [{low}, {high}]"
        );
    });
}

/// Light that reaches the camera only off a textured floor: a spot just under a grey ceiling
/// shines down on a dark patch of the floor (albedo 0.1, off centre) in a bright surround (0.9),
/// and the camera sees the ceiling alone, lit by the floor. Each VPL method's mean matches the
/// path tracer's (whose path vertices the furnace checks) within 3%: a method whose VPLs,
/// reverse VPLs or bundle vertices took the floor's Kd (1), or read the texture flipped or
/// transposed, would be several times too bright.
#[test]
fn light_off_a_textured_floor_reaches_the_ceiling_in_every_vpl_method() {
    let dir = Scratch::new("textures", "indirect");
    let (half, repeats) = (3.0f32, 1.0f32);
    let mut triangles = textured_plane(half, repeats, 0);
    triangles.extend(plane_y(half, 1.0, 1));
    let mut scene = scene(
        "textured floor under a spot",
        camera(
            Vec3::new(0.0, 0.05, 0.0),
            Vec3::new(0.0, 1.0, 0.0),
            Vec3::Z,
            90.0,
            16,
        ),
        triangles,
        vec![
            material("floor", 1.0, 0.0, 1.0, 0.0),
            material("ceiling", 0.5, 0.0, 1.0, 0.0),
        ],
    );
    // 16 x 16 texels over 6 x 6: texels 8..=14 across, rows 2..=8 down are dark, around the
    // spot's pool (texels 9..13, rows 3..7); the pool's mirror images across either axis, and
    // across the diagonal, fall on bright texels, so a flipped or swapped lookup is seen.
    let levels: Vec<f32> = (0..256)
        .map(|i| {
            let (x, y) = (i % 16, i / 16);
            if (8..=14).contains(&x) && (2..=8).contains(&y) {
                0.1
            } else {
                0.9
            }
        })
        .collect();
    scene
        .textures
        .push(grey_texture(16, 16, &levels, Wrap::Repeat));
    scene.materials[0].albedo_texture = Some(0);
    scene.lights.push(Light::Spot {
        position: Vec3::new(1.2, 0.9, -0.8),
        intensity: Vec3::splat(4.0),
        direction: Vec3::NEG_Y,
        cone_angle: 30.0,
        falloff_angle: 40.0,
    });
    with_gpu(|ctx| {
        let mean = |method: &str, params: &str| {
            common::luminance_mean(&render_method(ctx, &scene, method, params, &dir))
        };
        // bundles renders paths of up to two scattering events (light, x1, x2 = x3 on the
        // ceiling, camera), so it is held to the path tracer cut there.
        // bir's means over seeds spread by about 3% at 16 frames here (0.00401 to 0.00423), the
        // path tracer's by about 1% at 512 spp: bir gets 4x the frames, the path tracer 2x.
        let full = mean("reference", "spp = 1024\nseed = 1");
        let two_bounces = mean("reference", "spp = 1024\nseed = 1\nmax_depth = 2");
        for (method, params, reference) in [
            ("ir", "frames = 16\nvpls = 256", full),
            ("bir", "frames = 64", full),
            ("bundles", "frames = 16", two_bounces),
        ] {
            let m = mean(method, params);
            eprintln!(
                "{method}: ceiling mean {m:.5}, the path tracer's {reference:.5}: {:.4}",
                m / reference
            );
            assert!(
                (m / reference - 1.0).abs() < 0.03,
                "{method}: {m} against {reference}"
            );
        }
    });
}

/// scenes/textured-cornell: map_Kd reads its PNG (repeated) and JPEG (`-clamp on`), the floor's
/// `vt` reach its triangles; a missing texture and one that is not an image are refused naming
/// the MTL file, the line and the image.
#[test]
fn an_obj_scene_reads_its_png_and_jpeg_textures_and_names_bad_ones() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/textured-cornell");
    let scene = irad::scene::load(&root.join("scene.toml")).unwrap();
    assert!(scene.warnings.is_empty(), "{:?}", scene.warnings);
    assert_eq!(scene.textures.len(), 2);
    let [checker, poster] = [0, 1].map(|k| &scene.textures[k]);
    assert_eq!(
        (checker.width, checker.height, checker.wrap),
        (64, 64, [Wrap::Repeat; 2])
    );
    assert_eq!(
        (poster.width, poster.height, poster.wrap),
        (128, 128, [Wrap::Clamp; 2])
    );
    // Texel (0, 0) is warm white, sRGB (230, 220, 200): linear 0.7913, 0.7157, 0.5776.
    let t = checker.texels[0];
    assert!(
        (t - Vec3::new(0.7913, 0.7157, 0.5776)).abs().max_element() < 1e-3,
        "{t}"
    );
    let floor = scene
        .materials
        .iter()
        .position(|m| m.name == "checker")
        .unwrap() as u32;
    assert_eq!(scene.materials[floor as usize].albedo_texture, Some(0));
    let floor_uvs: Vec<Vec2> = scene
        .triangles
        .iter()
        .filter(|t| t.material == floor)
        .flat_map(|t| t.uvs)
        .collect();
    assert!(floor_uvs.contains(&Vec2::new(4.0, 4.0)) && floor_uvs.contains(&Vec2::ZERO));

    let dir = Scratch::new("textures", "bad");
    for f in [
        "scene.toml",
        "textured-cornell.obj",
        "textured-cornell.mtl",
        "poster.jpg",
    ] {
        std::fs::copy(root.join(f), dir.0.join(f)).unwrap();
    }
    let e = irad::scene::load(&dir.0.join("scene.toml"))
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("checker.png") && e.contains("textured-cornell.mtl line 14: map_Kd checker.png"),
        "{e}"
    );
    std::fs::write(dir.0.join("checker.png"), "not an image").unwrap();
    let e = irad::scene::load(&dir.0.join("scene.toml"))
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("textured-cornell.mtl")
            && e.contains("material `checker` map_Kd (line 14)")
            && e.contains("not a PNG or JPEG"),
        "{e}"
    );
}
