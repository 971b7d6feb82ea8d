//! ReSTIR DI's temporal reuse across an animation's frames (src/methods/restir/mod.rs,
//! glsl/restir/reuse_restir_temporal.comp; RTXDI's temporal resampling): each frame of a
//! sequence rendered with one restir frame reuses the previous animation frame's reservoirs,
//! found by projecting the pixel's point through the previous camera, translated into this
//! frame's light table and weighed under the previous frame's lights.
//!
//! - A walk through a room where the camera moves and turns, a point light moves, one area
//!   light switches off and another on: every frame's image mean over seeds within noise of
//!   the path tracer's (direct light), and the reuse paying (relMSE below restir's without
//!   temporal reuse), so the history is used and not silently dropped.
//! - The moving sun across animation frames (its map changes every frame): every frame's mean
//!   within noise, the history paying (measured with 30 seeds: 0.997-0.998 +- 0.003 of the
//!   path tracer in frames 0-3, relMSE 1.5-2.1x below restir's without temporal reuse).
//! - A disocclusion: the camera slides past a panel in front of a lit wall. Where a pixel
//!   showed the panel in the previous frame and shows the wall now, the surface test must
//!   reject the history. The biased combination (1 / sum of M) shows it: with the test its
//!   mean there is the path tracer's; without it (thresholds wide open) the panel's dark
//!   reservoirs darken the wall by far more than the noise.
//!
//! Standard errors are those of per-render means over independent seeds (reuse correlates
//! pixels).

use crate::common;

use std::path::Path;

use glam::Vec3;
use irad::gpu::Context;
use irad::image::Image;
use irad::methods::gbuffer::PixelSampling;
use irad::methods::reference::{Reference, ReferenceSettings};
use irad::methods::{Method, Renderer};
use irad::scene::gpu::GpuScene;
use irad::scene::{self, Scene};
use irad::sequence;

use common::{luminance_mean, mean_and_stderr, with_gpu, Scratch};

/// An OBJ quad of corners `c` (a loop) in material `m`, wound so its geometric normal (the
/// emitting side of an emitter) points along `facing`.
fn quad(obj: &mut String, count: &mut u32, c: [Vec3; 4], facing: Vec3, m: &str) {
    let n = (c[1] - c[0]).cross(c[2] - c[0]);
    let c = if n.dot(facing) < 0.0 {
        [c[0], c[3], c[2], c[1]]
    } else {
        c
    };
    obj.push_str(&format!("usemtl {m}\n"));
    for p in c {
        obj.push_str(&format!("v {} {} {}\n", p.x, p.y, p.z));
    }
    let k = *count;
    obj.push_str(&format!("f {} {} {} {}\n", k + 1, k + 2, k + 3, k + 4));
    *count += 4;
}

/// A quad in the plane y = `y` over [x0, x1] x [z0, z1].
fn horizontal(x0: f32, x1: f32, y: f32, z0: f32, z1: f32) -> [Vec3; 4] {
    [
        Vec3::new(x0, y, z0),
        Vec3::new(x1, y, z0),
        Vec3::new(x1, y, z1),
        Vec3::new(x0, y, z1),
    ]
}

/// A quad in the plane z = `z` over [x0, x1] x [y0, y1].
fn upright(x0: f32, x1: f32, y0: f32, y1: f32, z: f32) -> [Vec3; 4] {
    [
        Vec3::new(x0, y0, z),
        Vec3::new(x1, y0, z),
        Vec3::new(x1, y1, z),
        Vec3::new(x0, y1, z),
    ]
}

fn write_scene(dir: &Path, obj: &str, mtl: &str, toml: &str) -> Scene {
    std::fs::write(dir.join("scene.obj"), format!("mtllib scene.mtl\n{obj}")).unwrap();
    std::fs::write(dir.join("scene.mtl"), mtl).unwrap();
    std::fs::write(dir.join("scene.toml"), toml).unwrap();
    scene::load(&dir.join("scene.toml")).unwrap()
}

const WALK_FRAMES: u32 = 6;

/// A room (floor, back wall, a panel standing on the floor), two area lights under the
/// ceiling and a point light; over 6 frames at 6 fps the camera moves and turns, the point
/// light moves, light `a` dims and goes out (frame 3 on: gone from the light table) and light
/// `b` comes on (from frame 3).
fn walk(dir: &Path, width: u32, height: u32) -> Scene {
    let (mut obj, mut count) = (String::new(), 0);
    let up = Vec3::Y;
    quad(
        &mut obj,
        &mut count,
        horizontal(-3.0, 3.0, 0.0, -3.0, 3.0),
        up,
        "floor",
    );
    quad(
        &mut obj,
        &mut count,
        upright(-3.0, 3.0, 0.0, 3.0, -3.0),
        Vec3::Z,
        "wall",
    );
    quad(
        &mut obj,
        &mut count,
        upright(-0.5, 0.5, 0.0, 1.5, 0.0),
        Vec3::Z,
        "panel",
    );
    quad(
        &mut obj,
        &mut count,
        horizontal(-1.5, -0.7, 2.5, -2.0, -1.2),
        -up,
        "a",
    );
    quad(
        &mut obj,
        &mut count,
        horizontal(0.7, 1.5, 2.5, -2.0, -1.2),
        -up,
        "b",
    );
    let mtl = "newmtl floor\nKd 0.6 0.6 0.6\nnewmtl wall\nKd 0.5 0.4 0.3\n\
               newmtl panel\nKd 0.3 0.5 0.3\nKs 0.3 0.3 0.3\nNs 20\n\
               newmtl a\nKd 0 0 0\nKe 6 6 5\nnewmtl b\nKd 0 0 0\nKe 3 4 6\n";
    let toml = format!(
        "[camera]\nposition = [-1.2, 1.6, 5]\nlook_at = [0, 0.8, 0]\nfov_y = 50\n\
         resolution = [{width}, {height}]\n[[mesh]]\nobj = \"scene.obj\"\n\
         [[light]]\nkind = \"point\"\nposition = [-1, 2, 1]\nintensity = [3, 3, 3]\n\
         [animation]\nframes = {WALK_FRAMES}\nfps = 6\n\
         [[animation.track]]\ntarget = \"camera.position\"\ntimes = [0.0, 0.8333]\n\
         values = [[-1.2, 1.6, 5], [1.0, 1.2, 4]]\n\
         [[animation.track]]\ntarget = \"camera.look_at\"\ntimes = [0.0, 0.8333]\n\
         values = [[0, 0.8, 0], [0.4, 0.8, -1]]\n\
         [[animation.track]]\ntarget = \"light[0].position\"\ntimes = [0.0, 0.8333]\n\
         values = [[-1, 2, 1], [1.2, 1.8, 0]]\n\
         [[animation.track]]\ntarget = \"material.a.emission\"\ntimes = [0.25, 0.42]\n\
         values = [1.0, 0.0]\n\
         [[animation.track]]\ntarget = \"material.b.emission\"\ntimes = [0.42, 0.58]\n\
         values = [0.0, 1.0]\n"
    );
    write_scene(dir, &obj, mtl, &toml)
}

/// The path tracer's direct light (one scattering event) of `still`, one image per seed.
fn reference_images(
    ctx: &Context,
    still: &Scene,
    spp: u32,
    seeds: u32,
    pixels: PixelSampling,
) -> Vec<Image> {
    let gpu = GpuScene::upload(ctx, still).unwrap();
    let reference = Renderer::<Reference>::new(ctx).unwrap();
    (0..seeds)
        .map(|seed| {
            let settings = ReferenceSettings {
                spp,
                seed: 900 + seed,
                max_depth: 1,
                pixels,
                ..Default::default()
            };
            let out = reference
                .render(ctx, still, &gpu, &settings, |_, _| {})
                .unwrap();
            assert_eq!(out.nonfinite_estimates, 0);
            out.image
        })
        .collect()
}

/// Restir with `params` (one restir frame per animation frame), a sequence of `frames` per
/// seed: images[seed][frame].
fn restir_sequences(
    ctx: &Context,
    scene: &Scene,
    params: &str,
    frames: u32,
    seeds: u32,
) -> Vec<Vec<Image>> {
    (0..seeds)
        .map(|seed| {
            let params: toml::Table =
                toml::from_str(&format!("frames = 1\nseed = {}\n{params}", 100 + 17 * seed))
                    .unwrap();
            let method = Method::from_params("restir", &params).unwrap();
            let mut images = Vec::new();
            sequence::render_frames(ctx, scene, &method, 0..frames, |f, _, out| {
                assert_eq!(out.nonfinite_estimates, 0, "frame {f}");
                images.push(out.image);
                Ok(())
            })
            .unwrap();
            images
        })
        .collect()
}

/// The mean over pixels of (a - r)^2 / (r^2 + 1e-3), r's luminance.
fn rel_mse(a: &Image, r: &Image) -> f64 {
    let lum = |p: &[f32; 3]| 0.2126 * p[0] as f64 + 0.7152 * p[1] as f64 + 0.0722 * p[2] as f64;
    let sum: f64 = a
        .pixels
        .iter()
        .zip(&r.pixels)
        .map(|(x, y)| {
            let (x, y) = (lum(x), lum(y));
            (x - y).powi(2) / (y * y + 1e-3)
        })
        .sum();
    sum / a.pixels.len() as f64
}

/// The per-pixel mean of `images`.
fn mean_image(images: &[&Image]) -> Image {
    let mut mean = images[0].clone();
    for (i, p) in mean.pixels.iter_mut().enumerate() {
        for (c, value) in p.iter_mut().enumerate() {
            *value = (images.iter().map(|im| im.pixels[i][c] as f64).sum::<f64>()
                / images.len() as f64) as f32;
        }
    }
    mean
}

/// Restir over `frames` of `scene` with and without temporal reuse (pixel centres), each
/// frame's mean over seeds against the path tracer's direct light (4 x 512 spp) and its relMSE
/// with the history against without: the failures, each frame's figures printed under `name`.
/// The history must pay by `pays_by` (relMSE without over with) in the frames `pays_in` takes.
fn check_frames(
    ctx: &Context,
    name: &str,
    scene: &Scene,
    frames: u32,
    seeds: u32,
    pays_in: impl Fn(u32) -> bool,
    pays_by: f64,
) -> Vec<String> {
    // At pixel centres, so that the error is restir's and not the pixel filter's (an emitter's
    // edge at 1 sample per pixel).
    let with = restir_sequences(ctx, scene, "pixel_centres = true", frames, seeds);
    let without = restir_sequences(
        ctx,
        scene,
        "pixel_centres = true\ntemporal = false",
        frames,
        seeds,
    );
    let mut failures = Vec::new();
    for f in 0..frames {
        let still = scene.at_frame(f).unwrap();
        let references = reference_images(ctx, &still, 512, 4, PixelSampling::Centres);
        let reference_means: Vec<f64> = references.iter().map(luminance_mean).collect();
        let (r, r_se) = mean_and_stderr(&reference_means);
        let means: Vec<f64> = with
            .iter()
            .map(|s| luminance_mean(&s[f as usize]))
            .collect();
        let (m, m_se) = mean_and_stderr(&means);
        let ratio = m / r;
        let se = ratio * ((m_se / m).powi(2) + (r_se / r).powi(2)).sqrt();
        let reference = mean_image(&references.iter().collect::<Vec<_>>());
        let error = |runs: &[Vec<Image>]| {
            runs.iter()
                .map(|s| rel_mse(&s[f as usize], &reference))
                .sum::<f64>()
                / runs.len() as f64
        };
        let (e_with, e_without) = (error(&with), error(&without));
        eprintln!(
            "{name} frame {f}: mean / reference {ratio:.4} ± {se:.4}; relMSE {e_with:.4} with the \
             history, {e_without:.4} without ({:.2}x)",
            e_without / e_with
        );
        if se >= 0.02 {
            failures.push(format!("frame {f}: too noisy to test ({se:.4})"));
        }
        if (ratio - 1.0).abs() >= 4.0 * se {
            failures.push(format!(
                "frame {f}: restir with the previous frame's reservoirs {ratio:.4} of the path \
                 tracer, off by more than 4 standard errors ({se:.4})"
            ));
        }
        if pays_in(f) && e_without < pays_by * e_with {
            failures.push(format!(
                "frame {f}: the history does not pay (relMSE {e_with:.4} with it, {e_without:.4} without)"
            ));
        }
    }
    failures
}

#[test]
#[ignore = "statistical tier: scripts/test.sh --statistical"]
fn a_moving_camera_and_moving_switching_lights_keep_every_frame_unbiased() {
    let scratch = Scratch::new("motion", "walk");
    let scene = walk(&scratch.0, 24, 16);
    with_gpu(|ctx| {
        // Not where light a has just left the table (frame 3) and the frame after: the history
        // resampled for it weighs in at the balance heuristic's share and delivers little
        // (docs/DESIGN.md "State across frames").
        let failures = check_frames(
            ctx,
            "walk",
            &scene,
            WALK_FRAMES,
            10,
            |f| [1, 2, 5].contains(&f),
            1.25,
        );
        assert!(failures.is_empty(), "{failures:#?}");
    });
}

const PANEL_FRAMES: u32 = 4;
const PANEL_HALF: f32 = 0.6;
const PANEL_Z: f32 = 2.0;

/// A lit wall (z = 0, facing the camera) and a panel 2 in front of it, unlit: the only light,
/// a small emitter just behind the panel, faces the wall. The camera (z = 5) slides from
/// x = -1.2 to 1.2 over 4 frames looking straight ahead, so each frame uncovers a strip of
/// wall beside the panel.
fn panel(dir: &Path, width: u32, height: u32) -> Scene {
    let (mut obj, mut count) = (String::new(), 0);
    let h = PANEL_HALF;
    quad(
        &mut obj,
        &mut count,
        upright(-4.0, 4.0, -3.0, 3.0, 0.0),
        Vec3::Z,
        "wall",
    );
    quad(
        &mut obj,
        &mut count,
        upright(-h, h, -h, h, PANEL_Z),
        Vec3::Z,
        "panel",
    );
    quad(
        &mut obj,
        &mut count,
        upright(-0.3, 0.3, -0.3, 0.3, 1.8),
        -Vec3::Z,
        "light",
    );
    let mtl = "newmtl wall\nKd 0.5 0.5 0.5\nnewmtl panel\nKd 0.5 0.5 0.5\n\
               newmtl light\nKd 0 0 0\nKe 20 20 20\n";
    let end = PANEL_FRAMES - 1;
    let toml = format!(
        "[camera]\nposition = [-1.2, 0, 5]\nlook_at = [-1.2, 0, 0]\nfov_y = 40\n\
         resolution = [{width}, {height}]\n[[mesh]]\nobj = \"scene.obj\"\n\
         [animation]\nframes = {PANEL_FRAMES}\nfps = 1\n\
         [[animation.track]]\ntarget = \"camera.position\"\ntimes = [0.0, {end}.0]\n\
         values = [[-1.2, 0, 5], [1.2, 0, 5]]\n\
         [[animation.track]]\ntarget = \"camera.look_at\"\ntimes = [0.0, {end}.0]\n\
         values = [[-1.2, 0, 0], [1.2, 0, 0]]\n"
    );
    write_scene(dir, &obj, mtl, &toml)
}

/// Whether the ray from `origin` along `d` meets the panel.
fn meets_panel(origin: Vec3, d: Vec3) -> bool {
    let t = (PANEL_Z - origin.z) / d.z;
    let p = origin + t * d;
    t > 0.0 && p.x.abs() < PANEL_HALF && p.y.abs() < PANEL_HALF
}

/// The pixels of frame `f` whose centre shows the wall while the previous frame's pixel where
/// that point falls showed the panel: where history must be rejected.
fn disoccluded(scene: &Scene, f: u32) -> Vec<bool> {
    let (now, before) = (
        scene.at_frame(f).unwrap().camera,
        scene.at_frame(f - 1).unwrap().camera,
    );
    let (w, h) = (now.width, now.height);
    let (forward, right, up) = before.basis();
    let t = (before.fov_y.to_radians() * 0.5).tan();
    let aspect = w as f32 / h as f32;
    let mut mask = Vec::new();
    for y in 0..h {
        for x in 0..w {
            let d = now.direction(x as f32 + 0.5, y as f32 + 0.5);
            if meets_panel(now.position, d) {
                mask.push(false);
                continue;
            }
            let wall = now.position + (-now.position.z / d.z) * d;
            // The wall point through the previous camera (camera.glsl's mapping inverted).
            let v = wall - before.position;
            let z = v.dot(forward);
            let px = (v.dot(right) / (z * t * aspect) + 1.0) * 0.5 * w as f32;
            let py = (1.0 - v.dot(up) / (z * t)) * 0.5 * h as f32;
            let centre = before.direction(px.floor() + 0.5, py.floor() + 0.5);
            mask.push(meets_panel(before.position, centre));
        }
    }
    mask
}

fn masked_mean(image: &Image, mask: &[bool]) -> f64 {
    let (mut sum, mut n) = (0.0, 0);
    for (p, &m) in image.pixels.iter().zip(mask) {
        if m {
            sum += 0.2126 * p[0] as f64 + 0.7152 * p[1] as f64 + 0.0722 * p[2] as f64;
            n += 1;
        }
    }
    sum / n as f64
}

#[test]
fn disoccluded_pixels_reject_the_previous_frames_reservoirs() {
    let scratch = Scratch::new("motion", "panel");
    let scene = panel(&scratch.0, 32, 24);
    let seeds = 6;
    // Temporal reuse alone (no neighbours), at pixel centres so that the masks are exact.
    let common = "combination = \"biased\"\nneighbours = 0\npixel_centres = true\n";
    with_gpu(|ctx| {
        let tested = restir_sequences(ctx, &scene, common, PANEL_FRAMES, seeds);
        let untested = restir_sequences(
            ctx,
            &scene,
            &format!("{common}temporal_normal = 0\ntemporal_depth = 1000000\n"),
            PANEL_FRAMES,
            seeds,
        );
        for f in 1..PANEL_FRAMES {
            let mask = disoccluded(&scene, f);
            let pixels = mask.iter().filter(|&&m| m).count();
            assert!(pixels >= 10, "frame {f}: {pixels} disoccluded pixels");
            let still = scene.at_frame(f).unwrap();
            let reference: Vec<f64> = reference_images(ctx, &still, 256, 4, PixelSampling::Centres)
                .iter()
                .map(|im| masked_mean(im, &mask))
                .collect();
            let (r, r_se) = mean_and_stderr(&reference);
            let ratio = |runs: &[Vec<Image>]| {
                let m: Vec<f64> = runs
                    .iter()
                    .map(|s| masked_mean(&s[f as usize], &mask))
                    .collect();
                let (m, m_se) = mean_and_stderr(&m);
                (
                    m / r,
                    m / r * ((m_se / m).powi(2) + (r_se / r).powi(2)).sqrt(),
                )
            };
            let ((with, with_se), (without, without_se)) = (ratio(&tested), ratio(&untested));
            eprintln!(
                "panel frame {f}, {pixels} disoccluded pixels: mean / reference {with:.4} ± \
                 {with_se:.4} with the surface test, {without:.4} ± {without_se:.4} without"
            );
            assert!(
                with_se < 0.03,
                "frame {f}: too noisy to test ({with_se:.4})"
            );
            assert!(
                (with - 1.0).abs() < 4.0 * with_se,
                "frame {f}: with the surface test {with:.4} of the path tracer ({with_se:.4})"
            );
            assert!(
                without < 1.0 - 8.0 * without_se.max(with_se),
                "frame {f}: without the surface test {without:.4}, not told apart"
            );
        }
    });
}

/// The moving sun (a map that changes every frame) across animation frames: each frame's
/// history is weighed under the previous frame's map, uploaded from its scene. Every frame's
/// mean over seeds within noise of the path tracer's direct light, and the history paying.
#[test]
#[ignore = "statistical tier: scripts/test.sh --statistical"]
fn a_map_that_changes_every_frame_keeps_every_frame_unbiased() {
    let scene = common::scene_file("moving-sun-sequence", 24, 16);
    with_gpu(|ctx| {
        let failures = check_frames(ctx, "moving sun", &scene, 4, 16, |f| f >= 1, 1.0);
        assert!(failures.is_empty(), "{failures:#?}");
    });
}
