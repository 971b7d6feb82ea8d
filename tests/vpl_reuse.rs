//! ir's VPL reuse across animation frames (`--reuse K`, src/methods/ir/reuse.rs): a frame that
//! keeps K - 1 classes of light paths from earlier frames, re-weighed for where a moving point
//! light is now, must be as bright, half by half, as one whose paths are all fresh; and the
//! paths are kept only where they may be (a sequence's later frames, the same light table).

use crate::common;

use std::path::Path;

use irad::gpu::Context;
use irad::image::Image;
use irad::methods::Method;
use irad::scene::{self, Scene};
use irad::sequence;

use common::{mean_and_stderr, with_gpu, Scratch};

const FRAMES: u32 = 5;

/// A closed room split at the ceiling by a hanging partition (x = 0, down to y = 1.6), lit by a
/// point light below the partition's edge that crosses from the left half to the right over
/// the frames (the ceiling behind the partition goes dark and the other side lights up, so kept
/// VPLs turn invisible from the light and new surfaces get light only the fresh class can
/// reach), and by a spot light under the ceiling that crosses the other way and tilts (its
/// cone moves over surfaces the kept paths' cones did not cover).
fn crossing_room(dir: &Path, width: u32, height: u32) -> Scene {
    let mut obj = String::from("mtllib scene.mtl\n");
    let mut vertices = 0;
    let mut quad = |obj: &mut String, c: [[f32; 3]; 4], m: &str| {
        obj.push_str(&format!("usemtl {m}\n"));
        for p in c {
            obj.push_str(&format!("v {} {} {}\n", p[0], p[1], p[2]));
        }
        let k = vertices;
        obj.push_str(&format!("f {} {} {} {}\n", k + 1, k + 2, k + 3, k + 4));
        vertices += 4;
    };
    // Corners wound so the normals face into the room (two-sided shading either way).
    let (x0, x1, y0, y1, z0, z1) = (-2.0, 2.0, 0.0, 3.0, -2.0, 2.0);
    quad(
        &mut obj,
        [[x0, y0, z0], [x0, y0, z1], [x1, y0, z1], [x1, y0, z0]],
        "floor",
    );
    quad(
        &mut obj,
        [[x0, y1, z0], [x1, y1, z0], [x1, y1, z1], [x0, y1, z1]],
        "ceiling",
    );
    quad(
        &mut obj,
        [[x0, y0, z0], [x1, y0, z0], [x1, y1, z0], [x0, y1, z0]],
        "wall",
    );
    quad(
        &mut obj,
        [[x0, y0, z1], [x0, y1, z1], [x1, y1, z1], [x1, y0, z1]],
        "wall",
    );
    quad(
        &mut obj,
        [[x0, y0, z0], [x0, y1, z0], [x0, y1, z1], [x0, y0, z1]],
        "red",
    );
    quad(
        &mut obj,
        [[x1, y0, z0], [x1, y0, z1], [x1, y1, z1], [x1, y1, z0]],
        "green",
    );
    quad(
        &mut obj,
        [[0.0, 1.6, z0], [0.0, 1.6, z1], [0.0, y1, z1], [0.0, y1, z0]],
        "wall",
    );
    std::fs::write(dir.join("scene.obj"), obj).unwrap();
    std::fs::write(
        dir.join("scene.mtl"),
        "newmtl floor\nKd 0.7 0.7 0.7\nnewmtl ceiling\nKd 0.8 0.8 0.8\n\
         newmtl wall\nKd 0.6 0.6 0.6\nnewmtl red\nKd 0.7 0.2 0.2\nnewmtl green\nKd 0.2 0.7 0.2\n",
    )
    .unwrap();
    std::fs::write(
        dir.join("scene.toml"),
        format!(
            "[camera]\nposition = [0, 1.5, 1.9]\nlook_at = [0, 1.2, -2]\nfov_y = 80\n\
             resolution = [{width}, {height}]\n[[mesh]]\nobj = \"scene.obj\"\n\
             [[light]]\nkind = \"point\"\nposition = [-1.5, 1.3, -0.5]\n\
             intensity = [4, 4, 4]\n\
             [[light]]\nkind = \"spot\"\nposition = [1.2, 2.5, 1.0]\n\
             direction = [0, -1, 0]\nintensity = [3, 2.5, 2]\n\
             cone_angle = 30\nfalloff_angle = 50\n\
             [animation]\nframes = {FRAMES}\nfps = 4\n\
             [[animation.track]]\ntarget = \"light[0].position\"\ntimes = [0.0, 1.0]\n\
             values = [[-1.5, 1.3, -0.5], [1.5, 1.3, 0.5]]\n\
             [[animation.track]]\ntarget = \"light[1].position\"\ntimes = [0.0, 1.0]\n\
             values = [[1.2, 2.5, 1.0], [-1.2, 2.5, -1.0]]\n\
             [[animation.track]]\ntarget = \"light[1].direction\"\ntimes = [0.0, 1.0]\n\
             values = [[0, -1, 0], [0.6, -0.8, 0]]\n"
        ),
    )
    .unwrap();
    scene::load(&dir.join("scene.toml")).unwrap()
}

/// Each seed's frames 0..FRAMES of ir with `params`, and each frame's `reuse_kept_paths` stat.
fn sequences(ctx: &Context, scene: &Scene, params: &str, seeds: u32) -> Vec<Vec<(Image, f64)>> {
    (0..seeds)
        .map(|seed| {
            let params: toml::Table = toml::from_str(&format!(
                "frames = 1\nvpls = 128\ndirect_spp = 4\nseed = {}\n{params}",
                1000 + 31 * seed
            ))
            .unwrap();
            let method = Method::from_params("ir", &params).unwrap();
            let mut frames = Vec::new();
            sequence::render_frames(ctx, scene, &method, 0..FRAMES, |f, _, out| {
                assert_eq!(out.nonfinite_estimates, 0, "frame {f}");
                let kept = out
                    .stats
                    .iter()
                    .find(|(name, _)| name == "reuse_kept_paths")
                    .map_or(-1.0, |s| s.1);
                frames.push((out.image, kept));
                Ok(())
            })
            .unwrap();
            frames
        })
        .collect()
}

/// The mean luminance of the left and the right half of `image`.
fn halves(image: &Image) -> [f64; 2] {
    let lum = |p: &[f32; 3]| 0.2126 * p[0] as f64 + 0.7152 * p[1] as f64 + 0.0722 * p[2] as f64;
    let (w, h) = (image.width as usize, image.height as usize);
    let mut sums = [0.0; 2];
    for y in 0..h {
        for x in 0..w {
            sums[usize::from(x >= w / 2)] += lum(&image.pixels[y * w + x]);
        }
    }
    sums.map(|s| s / (w * h / 2) as f64)
}

/// Measured (release, lavapipe): at 48 seeds every frame's halves within 1.6 standard errors of
/// the fresh paths'; with the re-weighing left out (kept VPLs at their old powers) frames 2-4
/// are 12-23% off and fail at 10 seeds. More seeds: IRAD_TEST_SEEDS=48.
#[test]
fn kept_paths_light_each_half_of_the_room_as_fresh_ones_do() {
    with_gpu(|ctx| {
        let scratch = Scratch::new("vpl-reuse", "crossing");
        let scene = crossing_room(&scratch.0, 16, 12);
        let seeds = std::env::var("IRAD_TEST_SEEDS").map_or(10, |s| s.parse().unwrap());
        let fresh = sequences(ctx, &scene, "reuse = 1", seeds);
        let kept = sequences(ctx, &scene, "reuse = 4", seeds);
        let mut failures = Vec::new();
        for f in 0..FRAMES as usize {
            // Kept from earlier frames: 3 of 4 classes from frame 1 on, none in frame 0.
            let expected = if f == 0 { 0.0 } else { 0.75 };
            for run in &kept {
                assert_eq!(run[f].1, expected, "frame {f}: reuse_kept_paths");
            }
            assert!(
                fresh.iter().all(|run| run[f].1 == -1.0),
                "reuse = 1 keeps nothing"
            );
            for half in 0..2 {
                // Paired by seed (the two share the direct light's samples): the mean and
                // standard error of the per-seed differences, against the fresh paths' mean.
                let differences: Vec<f64> = kept
                    .iter()
                    .zip(&fresh)
                    .map(|(a, b)| halves(&a[f].0)[half] - halves(&b[f].0)[half])
                    .collect();
                let (d, d_se) = mean_and_stderr(&differences);
                let (b, _) = mean_and_stderr(
                    &fresh
                        .iter()
                        .map(|r| halves(&r[f].0)[half])
                        .collect::<Vec<_>>(),
                );
                eprintln!("frame {f} half {half}: fresh {b:.5}, kept - fresh {d:+.5} ± {d_se:.5}");
                if d.abs() > 4.0 * d_se.max(0.002 * b) {
                    failures.push(format!(
                        "frame {f} half {half}: kept paths {:.5}, fresh {b:.5} (difference ± \
                         {d_se:.5})",
                        b + d
                    ));
                }
            }
        }
        assert!(failures.is_empty(), "{}", failures.join("\n"));
    });
}
