//! Light-field luminaires (Lu 14 ch. 4): the GPU sampling tables and sampler against
//! the f64 mirror, every strategy's mean against the brute force, the strategies at equal
//! error, the closed-form disk, where samples go, and the estimator near the image plane.

use crate::common;

use irad::gpu::Commands;
use irad::methods::lightfield::tables::LuminaireTables;
use irad::methods::rebuild::TableRebuild;
use irad::methods::Renderer;
use irad::sampling::luminaire::LuminaireSampler;
use irad::scene::luminaire::{Basis, Emitter, Geometry, Luminaire};

use common::with_gpu;

/// The GPU's conditional CDFs, marginal CDFs and summed-area tables of a generated headlight
/// (5 x 3 images of 24 x 16 texels) against sampling/restricted.rs's f64 tables, at every knot,
/// within 1e-5 of the image's total (f32 scans).
#[test]
fn gpu_tables_match_the_f64_mirror() {
    with_gpu(|ctx| {
        let geometry = Geometry {
            grid: [5, 3],
            pitch: [0.02, 0.03],
            basis: Basis::QuadraticBSpline,
            delta: 0.05,
            image_size: [0.3, 0.2],
            resolution: [24, 16],
        };
        let headlight = Emitter::Headlight {
            radius: 0.05,
            radiance: 20.0,
            sharpness: 12.0,
            tilt: 3.0,
        };
        let lum = Luminaire::from_emitter(geometry, |u, s| headlight.radiance(u, s, 0.05), "test");
        let mirror = LuminaireSampler::new(&lum);
        let tables = LuminaireTables::new(ctx, &lum).unwrap();
        let mut cmd = Commands::new(ctx).unwrap();
        cmd.pass("luminaire tables", |cmd| tables.record(cmd))
            .unwrap();
        cmd.submit_and_wait().unwrap();
        let (rs, rt) = (24usize, 16usize);
        let column_cdf = tables.column_cdf.read().unwrap();
        let marginal = tables.marginal_cdf.read().unwrap();
        let sat = tables.sat.read().unwrap();
        let totals = tables.image_totals.read().unwrap();
        let mut lit = 0;
        for (m, image) in mirror.images.iter().enumerate() {
            let total = image.marginal_knot(rs);
            if total > 0.0 {
                lit += 1;
            }
            let tolerance = 1e-5 * total.max(1e-30);
            let close = |gpu: f32, cpu: f64, what: &str| {
                assert!(
                    (gpu as f64 - cpu).abs() <= tolerance,
                    "image {m} {what}: GPU {gpu} against {cpu} (total {total})"
                );
            };
            close(totals[m], total, "total");
            for s in 0..rs {
                close(
                    marginal[m * rs + s],
                    image.marginal_knot(s + 1),
                    &format!("marginal at {s}"),
                );
                for t in 0..rt {
                    close(
                        column_cdf[(m * rs + s) * rt + t],
                        image.column_knot(s, t + 1),
                        &format!("column {s} at {t}"),
                    );
                    close(
                        sat[(m * rt + t) * rs + s],
                        image.sat_knot(s + 1, t + 1),
                        &format!("SAT at ({s}, {t})"),
                    );
                }
            }
        }
        assert!(lit >= 10, "only {lit} of 15 images carry light");
    });
}

/// The GPU's restricted sampler (glsl/include/luminaire_tables.glsl, through
/// draw_luminaire_samples.comp) against the f64 mirror's pdf, C / A: for windows of several
/// sizes and positions, one reaching past the image's border, and both searches, each draw's
/// reported pdf (the density it realised) matches the mirror's at its texel within 1e-3 and
/// the f32 rounding of the sums it came from (or it lies within 1e-3 texel of a texel edge,
/// where f32 may pick the neighbour), draws stay in the window, the histogram over the texels
/// passes a chi-square test, and the secant search takes fewer steps than binary search.
#[test]
fn gpu_restricted_draws_follow_their_pdf() {
    use irad::methods::lightfield::tables::RestrictedDraws;
    use irad::sampling::restricted::{Marginal, Window};
    with_gpu(|ctx| {
        let geometry = Geometry {
            grid: [3, 3],
            pitch: [0.03, 0.03],
            basis: Basis::Bilinear,
            delta: 0.05,
            image_size: [0.3, 0.3],
            resolution: [32, 24],
        };
        let headlight = Emitter::Headlight {
            radius: 0.04,
            radiance: 20.0,
            sharpness: 6.0,
            tilt: 3.0,
        };
        let lum = Luminaire::from_emitter(geometry, |u, s| headlight.radiance(u, s, 0.05), "test");
        let mirror = LuminaireSampler::new(&lum);
        let tables = LuminaireTables::new(ctx, &lum).unwrap();
        let n = 100_000u32;
        let draws = RestrictedDraws::new(ctx, n).unwrap();
        let m = 4usize;
        let image = &mirror.images[m];
        let (rs, rt) = (32usize, 24usize);
        let mut steps = [0.0f64; 2];
        for (k, w) in [
            [0.0f32, 32.0, 0.0, 24.0],
            [3.4, 27.9, 2.2, 13.6],
            [-5.0, 7.5, -3.0, 8.2],
            [14.3, 17.8, 8.6, 10.1],
        ]
        .into_iter()
        .enumerate()
        {
            let window = Window {
                s0: w[0] as f64,
                s1: w[1] as f64,
                t0: w[2] as f64,
                t1: w[3] as f64,
            }
            .clamped(rs, rt);
            for (which, secant) in [false, true].into_iter().enumerate() {
                let mut cmd = Commands::new(ctx).unwrap();
                cmd.pass("luminaire tables", |cmd| tables.record(cmd))
                    .unwrap();
                cmd.pass("draws", |cmd| {
                    draws.record(cmd, &tables, m as u32, w, secant, 40 + k as u32)
                })
                .unwrap();
                cmd.submit_and_wait().unwrap();
                let mut counts = vec![0u32; rs * rt];
                for d in &draws.draws.read().unwrap() {
                    let (s, t) = (d[0] as f64, d[1] as f64);
                    assert!(
                        d[2] > 0.0,
                        "window {w:?}: a draw failed (A = {})",
                        image.window_integral(window)
                    );
                    assert!(
                        s >= window.s0 - 1e-4
                            && s <= window.s1 + 1e-4
                            && t >= window.t0 - 1e-4
                            && t <= window.t1 + 1e-4,
                        "({s}, {t}) outside {window:?}"
                    );
                    let texel = ((s as usize).min(rs - 1), (t as usize).min(rt - 1));
                    let p = image.pdf(window, texel, Marginal::Windowed);
                    let edge = |x: f64| (x - x.round()).abs() < 1e-3;
                    // The reported pdf is the density the draw realised, from f32 summed-area
                    // and column sums: their differences carry a few ulps of the image's and
                    // the column's totals, relative to the column's windowed mass and C.
                    let rounding = 1e-6
                        * (image.marginal_knot(rs) / image.windowed_column(texel.0, window)
                            + image.whole_column(texel.0) / image.texel(texel.0, texel.1));
                    assert!(
                        (d[2] as f64 - p).abs() <= (1e-3 + rounding) * p || edge(s) || edge(t),
                        "window {w:?}: reported pdf {} against {p} at {texel:?}",
                        d[2]
                    );
                    counts[texel.1 * rs + texel.0] += 1;
                    steps[which] += d[3] as f64;
                }
                let (mut chi2, mut cells) = (0.0, 0);
                for j in 0..rt {
                    for i in 0..rs {
                        let ds = (window.s1.min(i as f64 + 1.0) - window.s0.max(i as f64)).max(0.0);
                        let dt = (window.t1.min(j as f64 + 1.0) - window.t0.max(j as f64)).max(0.0);
                        let e = n as f64 * image.pdf(window, (i, j), Marginal::Windowed) * ds * dt;
                        let o = counts[j * rs + i] as f64;
                        if e == 0.0 {
                            assert_eq!(
                                o, 0.0,
                                "window {w:?}: texel ({i}, {j}) has pdf 0 but {o} draws"
                            );
                        } else if e >= 5.0 {
                            chi2 += (o - e).powi(2) / e;
                            cells += 1;
                        }
                    }
                }
                let dof = (cells as f64 - 1.0).max(1.0);
                eprintln!("window {w:?}, secant {secant}: chi^2 {chi2:.1} over {dof}");
                assert!(chi2 / dof < 1.6, "window {w:?}: chi^2 {chi2:.1} / {dof}");
            }
        }
        // Above the cut-off line the images are black: a window there holds nothing and every
        // draw fails, with pdf 0.
        let empty = [0.0f32, 32.0, 20.0, 24.0];
        let e = Window {
            s0: 0.0,
            s1: 32.0,
            t0: 20.0,
            t1: 24.0,
        };
        assert!(image.window_integral(e) <= 1e-9 * image.marginal_knot(32));
        let mut cmd = Commands::new(ctx).unwrap();
        cmd.pass("luminaire tables", |cmd| tables.record(cmd))
            .unwrap();
        cmd.pass("draws", |cmd| {
            draws.record(cmd, &tables, m as u32, empty, true, 9)
        })
        .unwrap();
        cmd.submit_and_wait().unwrap();
        assert!(draws.draws.read().unwrap().iter().all(|d| d[2] == 0.0));
        let per_draw = |x: f64| x / (4.0 * n as f64);
        eprintln!(
            "search steps per draw: binary {:.2}, secant {:.2}",
            per_draw(steps[0]),
            per_draw(steps[1])
        );
        assert!(steps[1] < steps[0]);
    });
}

fn headlight_wall(width: u32, height: u32) -> irad::scene::Scene {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("scenes/failure/headlight-wall/scene.toml");
    let mut scene = irad::scene::load(&path).unwrap();
    scene.camera.width = width;
    scene.camera.height = height;
    scene
}

/// A smooth headlight (one lobe, image plane 5 cm out, 7 x 5 images of 32 x 32): images that
/// fill much of the image plane, so that the brute force converges in a test's time.
fn smooth_headlight() -> Luminaire {
    let geometry = Geometry {
        grid: [7, 5],
        pitch: [0.02, 0.03],
        basis: Basis::QuadraticBSpline,
        delta: 0.05,
        image_size: [0.4, 0.4],
        resolution: [32, 32],
    };
    let headlight = Emitter::Headlight {
        radius: 0.06,
        radiance: 20.0,
        sharpness: 12.0,
        tilt: 3.0,
    };
    Luminaire::from_emitter(geometry, |u, s| headlight.radiance(u, s, 0.05), "smooth")
}

fn render_lightfield(
    ctx: &irad::gpu::Context,
    scene: &irad::scene::Scene,
    settings: irad::methods::lightfield::LightfieldSettings,
) -> irad::methods::RenderOutput {
    use irad::methods::lightfield::Lightfield;
    let gpu = irad::scene::gpu::GpuScene::upload(ctx, scene).unwrap();
    let out = Renderer::<Lightfield>::new(ctx)
        .unwrap()
        .render(ctx, scene, &gpu, &settings, |_, _| {})
        .unwrap();
    assert_eq!(out.nonfinite_estimates, 0);
    out
}

/// Every strategy of `lightfield` against the brute force (uniform over each whole image, the
/// reference): on the near-field headlight scene with the smooth headlight (32 x 24, 8 frames,
/// K = 64 and K_max = 64), the image mean over 8 seeds within 1% of the brute force's (12
/// seeds of 2240 samples per pixel and frame), restricted also with the Halton points shared
/// by every pixel; the other methods decline the scene.
#[test]
#[ignore = "statistical tier: scripts/test.sh --statistical"]
fn every_lightfield_strategy_matches_the_brute_force() {
    use irad::methods::gbuffer::PixelSampling;
    use irad::methods::lightfield::{Lightfield, LightfieldSettings, Strategy};
    use irad::scene::gpu::GpuScene;
    with_gpu(|ctx| {
        let mut scene = headlight_wall(32, 24);
        scene.luminaires[0].luminaire = smooth_headlight();
        let gpu = GpuScene::upload(ctx, &scene).unwrap();
        let lf = Renderer::<Lightfield>::new(ctx).unwrap();
        let render_with = |strategy: Strategy, spp: u32, frames: u32, seed: u32, shared: bool| {
            let settings = LightfieldSettings {
                spp,
                frames,
                strategy,
                k_max: spp,
                seed,
                shared_samples: shared,
                pixels: PixelSampling::Centres,
                ..Default::default()
            };
            let out = lf.render(ctx, &scene, &gpu, &settings, |_, _| {}).unwrap();
            assert_eq!(out.nonfinite_estimates, 0);
            common::luminance_mean(&out.image)
        };
        let render = |strategy: Strategy, spp: u32, frames: u32, seed: u32| {
            render_with(strategy, spp, frames, seed, false)
        };
        let brute: Vec<f64> = (0..12)
            .map(|s| render(Strategy::BruteForce, 35 * 64, 8, 900 + s))
            .collect();
        let (reference, reference_error) = common::mean_and_stderr(&brute);
        eprintln!(
            "brute force: {reference:.5e} ± {:.4}",
            reference_error / reference
        );
        for (strategy, shared) in [
            (Strategy::Restricted, false),
            (Strategy::Uniform, false),
            (Strategy::Precomputed, false),
            (Strategy::Restricted, true),
        ] {
            let means: Vec<f64> = (0..8)
                .map(|s| render_with(strategy, 64, 8, 100 + s, shared) / reference)
                .collect();
            let (mean, stderr) = common::mean_and_stderr(&means);
            eprintln!(
                "{}{}: mean / brute force {mean:.4} ± {stderr:.4}",
                strategy.name(),
                if shared {
                    " (shared Halton points)"
                } else {
                    ""
                }
            );
            assert!(
                stderr < 0.005,
                "{}: standard error {stderr}",
                strategy.name()
            );
            assert!(
                (mean - 1.0).abs() < 0.01,
                "{}: mean {mean:.4} of the brute force's",
                strategy.name()
            );
        }
        assert!(reference_error / reference < 0.005);
        // The methods that do not model luminaires decline the scene.
        let reference =
            irad::methods::Method::new::<irad::methods::reference::Reference>(Default::default());
        let why = reference.declines(&scene).unwrap();
        assert!(
            why.contains("does not render light-field luminaires"),
            "{why}"
        );
    });
}

/// Lu 14 Fig. 4.13-4.14 on the near-field scene's faceted headlight (32 x 24, 4 frames, 4
/// seeds), relMSE against a split reference (restricted at K = 1024, 8 frames, two seeds):
/// uniform needs more than 3x restricted's samples for restricted's error at K = 64 (its error
/// at 3x is still above; the thesis: 4x), and precomputed at equal samples has more than 10x
/// the error (the thesis's Fig. 4.13 gap). The equal-error ratio is interpolated and printed.
#[test]
#[ignore = "statistical tier: scripts/test.sh --statistical"]
fn strategies_at_equal_error() {
    use irad::image::metrics;
    use irad::methods::gbuffer::PixelSampling;
    use irad::methods::lightfield::{Lightfield, LightfieldSettings, Strategy};
    use irad::scene::gpu::GpuScene;
    with_gpu(|ctx| {
        // 32 x 24 (48 x 36 before: precomputed had 117x restricted's error, 10x asserted, and
        // uniform at 3x the samples 2.3x, 1x asserted; uniform matched restricted at 5.3x the
        // samples). Measured at 32 x 24, the same view's 768 pixel centres over 4 seeds:
        // 169x, 2.0x and 4.2x.
        let scene = headlight_wall(32, 24);
        let gpu = GpuScene::upload(ctx, &scene).unwrap();
        let lf = Renderer::<Lightfield>::new(ctx).unwrap();
        let render = |strategy: Strategy, spp: u32, frames: u32, seed: u32| {
            let settings = LightfieldSettings {
                spp,
                frames,
                strategy,
                k_max: spp,
                seed,
                pixels: PixelSampling::Centres,
                ..Default::default()
            };
            lf.render(ctx, &scene, &gpu, &settings, |_, _| {})
                .unwrap()
                .image
        };
        let a = render(Strategy::Restricted, 1024, 8, 1);
        let b = render(Strategy::Restricted, 1024, 8, 2);
        let error = |strategy: Strategy, spp: u32| {
            (0..4)
                .map(|s| {
                    metrics::rel_mse_against_split_reference(
                        &render(strategy, spp, 4, 50 + s),
                        &a,
                        &b,
                    )
                    .unwrap()
                })
                .sum::<f64>()
                / 4.0
        };
        let restricted = error(Strategy::Restricted, 64);
        let precomputed = error(Strategy::Precomputed, 64);
        let uniform: Vec<(u32, f64)> = [64u32, 128, 192, 256, 384]
            .into_iter()
            .map(|spp| (spp, error(Strategy::Uniform, spp)))
            .collect();
        // Where uniform's error (log-log interpolated) falls to restricted's at K = 64.
        let equal = uniform.windows(2).find_map(|w| {
            let ((k0, e0), (k1, e1)) = (w[0], w[1]);
            (e0 >= restricted && e1 < restricted).then(|| {
                let t = (e0 / restricted).ln() / (e0 / e1).ln();
                (k0 as f64).ln() + t * ((k1 as f64).ln() - (k0 as f64).ln())
            })
        });
        eprintln!(
            "relMSE at K = 64: restricted {restricted:.3e}, precomputed {precomputed:.3e} ({:.1}x); uniform at K = {uniform:?}; uniform reaches restricted's error at {}",
            precomputed / restricted,
            equal.map_or("more than 384 samples".into(), |l| format!("{:.2}x the samples", l.exp() / 64.0))
        );
        assert!(
            precomputed > 10.0 * restricted,
            "precomputed {precomputed:.3e} against restricted {restricted:.3e}"
        );
        let at_3x = uniform.iter().find(|(k, _)| *k == 192).unwrap().1;
        assert!(
            at_3x > restricted,
            "uniform at 3x the samples: {at_3x:.3e} against {restricted:.3e}"
        );
    });
}

const DISK_RADIUS: f64 = 0.1;

/// A uniform Lambertian disk of radius 0.1 and radiance 1 turned into a luminaire (9 x 9
/// quadratic B-splines over the disk, image plane 0.2 out, 32 x 32 images over `image_size`).
fn disk_luminaire(image_size: f64) -> Luminaire {
    let r = DISK_RADIUS;
    let disk = Emitter::Disk {
        radius: r,
        radiance: 1.0,
    };
    let geometry = Geometry {
        grid: [9, 9],
        pitch: [2.0 * r / 8.0, 2.0 * r / 8.0],
        basis: Basis::QuadraticBSpline,
        delta: 0.2,
        image_size: [image_size, image_size],
        resolution: [32, 32],
    };
    Luminaire::from_emitter(geometry, |u, s| disk.radiance(u, s, 0.2), "disk")
}

/// The luminaire `height` above a grey (albedo 0.5) floor, aimed straight down, seen by a
/// camera 3 above the floor looking down with `fov` degrees.
fn disk_over_floor(luminaire: Luminaire, height: f32, fov: f32, size: u32) -> irad::scene::Scene {
    use common::shapes;
    use glam::Vec3;
    let camera = shapes::camera(
        Vec3::new(0.0, 3.0, 0.0),
        Vec3::ZERO,
        Vec3::new(0.0, 0.0, -1.0),
        fov,
        size,
    );
    let mut scene = shapes::scene(
        "disk-over-floor",
        camera,
        shapes::plane_y(4.0, 0.0, 0),
        vec![shapes::material("floor", 0.5, 0.0, 1.0, 0.0)],
    );
    scene
        .luminaires
        .push(irad::scene::luminaire::PlacedLuminaire {
            luminaire,
            position: Vec3::new(0.0, height, 0.0),
            x: Vec3::new(-1.0, 0.0, 0.0),
            y: Vec3::new(0.0, 0.0, -1.0),
            z: Vec3::new(0.0, -1.0, 0.0),
        });
    scene
}

/// The camera of the centre-pixel tests (`centre_ratio`): 8 x 8 pixels over 0.5 degrees. Only
/// the 4 x 4 centre pixels are compared, and they see the same floor (pixel centres to 1e-5,
/// the same footprints) and take as many samples as at 16 x 16 over 1 degree, where three
/// quarters of the image was rendered only to be thrown away (near_the_image_plane took 48 s).
const CENTRE_FOV: f32 = 0.5;
const CENTRE_SIZE: u32 = 8;

/// The 4 x 4 pixels about the image centre.
fn centre_pixels(scene: &irad::scene::Scene) -> Vec<(u32, u32)> {
    let (w, h) = (scene.camera.width, scene.camera.height);
    (h / 2 - 2..h / 2 + 2)
        .flat_map(|y| (w / 2 - 2..w / 2 + 2).map(move |x| (x, y)))
        .collect()
}

/// Their mean luminance (what the f64 mirror integrates: it samples the images' luminance).
fn centre_radiance(scene: &irad::scene::Scene, image: &irad::image::Image) -> f64 {
    let pixels = centre_pixels(scene);
    pixels
        .iter()
        .map(|&(x, y)| {
            let c = image.pixels[(y * image.width + x) as usize];
            0.2126 * c[0] as f64 + 0.7152 * c[1] as f64 + 0.0722 * c[2] as f64
        })
        .sum::<f64>()
        / pixels.len() as f64
}

/// The centre pixels' luminance over `expected`: the restricted strategy at K = 256, 64 frames,
/// pixel centres, over 4 seeds; (mean, standard error).
fn centre_ratio(ctx: &irad::gpu::Context, scene: &irad::scene::Scene, expected: f64) -> (f64, f64) {
    let runs: Vec<f64> = (0..4)
        .map(|seed| {
            let out = render_lightfield(
                ctx,
                scene,
                irad::methods::lightfield::LightfieldSettings {
                    spp: 256,
                    frames: 64,
                    seed,
                    pixels: irad::methods::gbuffer::PixelSampling::Centres,
                    ..Default::default()
                },
            );
            centre_radiance(scene, &out.image) / expected
        })
        .collect();
    common::mean_and_stderr(&runs)
}

/// Where pixel (x, y)'s centre sees the floor, in the frame of the scene's luminaire.
fn floor_point(scene: &irad::scene::Scene, x: u32, y: u32) -> glam::DVec3 {
    let d = scene.camera.direction(x as f32 + 0.5, y as f32 + 0.5);
    let o = scene.camera.position;
    let p = o + d * (-o.y / d.y);
    let placed = &scene.luminaires[0];
    let l = p - placed.position;
    glam::DVec3::new(
        l.dot(placed.x) as f64,
        l.dot(placed.y) as f64,
        l.dot(placed.z) as f64,
    )
}

/// The closed-form emitter through the whole GPU method: a uniform Lambertian disk (radius R,
/// radiance 1) 0.5 above a floor of albedo 0.5, on its axis, gives the floor E = pi R^2 /
/// (h^2 + R^2) and the radiance 0.5 E / pi; the restricted estimate (K = 256, 64 frames, 4
/// seeds, the 4 x 4 pixels about the axis: 13 mm of floor) is within 1% of it.
#[test]
fn a_disk_luminaire_lights_the_floor_as_the_closed_form_says() {
    with_gpu(|ctx| {
        let h = 0.5f64;
        let scene = disk_over_floor(disk_luminaire(0.5), h as f32, CENTRE_FOV, CENTRE_SIZE);
        let r = DISK_RADIUS;
        let exact = 0.5 * r * r / (h * h + r * r);
        let (mean, stderr) = centre_ratio(ctx, &scene, exact);
        eprintln!("disk on the floor's axis: lightfield / closed form {mean:.4} ± {stderr:.4}");
        assert!(stderr < 0.003, "standard error {stderr}");
        assert!((mean - 1.0).abs() < 0.01, "{mean:.4} of the closed form");
    });
}

/// Where the samples go (Eq. 4.16, "no samples are spent where A(p) = 0"): over a wide view
/// of the floor under the disk luminaire (images 0.3 wide, so the light ends on the floor),
/// each pixel's samples against the f64 mirror's A(p) at the pixel centre's floor point:
/// none wherever A(p) = 0, some wherever A(p) is above 1e-3 of its peak; both kinds occur.
#[test]
fn no_samples_where_no_window_holds_light() {
    use irad::methods::gbuffer::PixelSampling;
    use irad::methods::lightfield::LightfieldSettings;
    with_gpu(|ctx| {
        let size = 48u32;
        let height = 1.0f32;
        let luminaire = disk_luminaire(0.3);
        let mirror = LuminaireSampler::new(&luminaire);
        let scene = disk_over_floor(luminaire, height, 100.0, size);
        let out = render_lightfield(
            ctx,
            &scene,
            LightfieldSettings {
                spp: 64,
                frames: 1,
                pixels: PixelSampling::Centres,
                ..Default::default()
            },
        );
        let samples = &out.maps.iter().find(|(n, _)| n == "samples").unwrap().1;
        let areas: Vec<f64> = (0..size * size)
            .map(|k| {
                let p = floor_point(&scene, k % size, k / size);
                mirror.shares(p, 64, 64).iter().map(|s| s.area).sum()
            })
            .collect();
        let peak = areas.iter().cloned().fold(0.0, f64::max);
        let (mut dark, mut lit) = (0, 0);
        for (k, &area) in areas.iter().enumerate() {
            let taken = samples.pixels[k][0];
            if area == 0.0 {
                dark += 1;
                assert_eq!(taken, 0.0, "pixel {k}: A(p) = 0 but samples were taken");
            } else if area > 1e-3 * peak {
                lit += 1;
                assert!(taken > 0.0, "pixel {k}: A(p) = {area:.3e} but no samples");
            }
        }
        eprintln!("{dark} pixels with A(p) = 0, {lit} lit");
        assert!(dark > 100 && lit > 100, "dark {dark}, lit {lit}");
    });
}

/// Section 4.3.4: close to the image plane the restricted strategy integrates over the filter
/// plane. The floor under the disk luminaire at two heights straddling the switch (every
/// window 1.1 and 0.88 texels wide), and 0.2 mm beyond the image plane, where the image-plane
/// estimator loses every image to f32 rounding (measured: 0 of the light): the centre pixels
/// (K = 256, 64 frames, 4 seeds) against the f64 mirror's integral over U (a 48 x 48 midpoint
/// rule per basis, 0.02% from 512 x 512) at the same floor points, within 1%. (The light
/// field is piecewise constant in s, so near S the light changes by 5% from texel to texel:
/// the expectation is taken at each pixel.)
#[test]
fn near_the_image_plane_the_filter_plane_estimator_takes_over() {
    with_gpu(|ctx| {
        for above in [0.06f64, 0.045, 0.0002] {
            let h = 0.2 + above;
            let luminaire = disk_luminaire(0.5);
            let mirror = LuminaireSampler::new(&luminaire);
            let scene = disk_over_floor(luminaire, h as f32, CENTRE_FOV, CENTRE_SIZE);
            let pixels = centre_pixels(&scene);
            let expected = 0.5 / std::f64::consts::PI
                * pixels
                    .iter()
                    .map(|&(x, y)| {
                        let p = floor_point(&scene, x, y);
                        mirror.irradiance_over_filter_plane(p, 48, true)
                    })
                    .sum::<f64>()
                / pixels.len() as f64;
            let (mean, stderr) = centre_ratio(ctx, &scene, expected);
            eprintln!("{above} m beyond the image plane: lightfield / integral over U {mean:.4} ± {stderr:.4}");
            assert!(stderr < 0.003, "{above}: standard error {stderr}");
            assert!((mean - 1.0).abs() < 0.01, "{above}: {mean:.4}");
        }
    });
}

/// A luminaire whose atlases change (the tables rebuilt per frame): a sequence
/// of three (the faceted headlight lowered 0, 10 and 20 degrees). At frames 1, 2 and 4 the
/// GPU's tables are those of atlas f mod 3 (against the f64 mirror, 1e-5 of the total); and a
/// render of the two-atlas sequence [A, black] over 2 frames is half a 1-frame render of A
/// (the same seed: frame 0 draws the same numbers) to f32 rounding, so frame 1 shows atlas 1.
#[test]
fn a_sequence_of_atlases_rebuilds_the_tables_every_frame() {
    use irad::gpu::Commands;
    use irad::methods::gbuffer::PixelSampling;
    use irad::methods::lightfield::LightfieldSettings;
    with_gpu(|ctx| {
        let geometry = Geometry {
            grid: [5, 3],
            pitch: [0.03, 0.03],
            basis: Basis::QuadraticBSpline,
            delta: 0.2,
            image_size: [0.6, 0.6],
            resolution: [24, 16],
        };
        let reflector = Emitter::Reflector {
            radius: 0.06,
            radiance: 2000.0,
            facet: 0.012,
            beam: 2.0,
            spread: 30.0,
            tilt: 0.0,
        };
        let atlases: Vec<Luminaire> = [0.0, 10.0, 20.0]
            .iter()
            .map(|&t| {
                let e = reflector.tilted(t).unwrap();
                Luminaire::from_emitter(geometry, |u, s| e.radiance(u, s, 0.2), "seq")
            })
            .collect();
        let mut lum = atlases[0].clone();
        lum.sequence = atlases.iter().map(|l| l.images.clone()).collect();
        let tables = LuminaireTables::new(ctx, &lum).unwrap();
        assert!(tables.is_sequence());
        for frame in [1u32, 2, 4] {
            let mut cmd = Commands::new(ctx).unwrap();
            tables
                .record_frame(&mut cmd, frame, TableRebuild::WhenChanged)
                .unwrap();
            cmd.submit_and_wait().unwrap();
            let mirror = LuminaireSampler::new(&atlases[frame as usize % 3]);
            let sat = tables.sat.read().unwrap();
            let (rs, rt) = (24usize, 16usize);
            for (m, image) in mirror.images.iter().enumerate() {
                let tolerance = 1e-5 * image.marginal_knot(rs).max(1e-30);
                for t in 0..rt {
                    for s in 0..rs {
                        let (gpu, cpu) = (
                            sat[(m * rt + t) * rs + s] as f64,
                            image.sat_knot(s + 1, t + 1),
                        );
                        assert!(
                            (gpu - cpu).abs() <= tolerance,
                            "frame {frame}, image {m}, SAT at ({s}, {t}): {gpu} against {cpu}"
                        );
                    }
                }
            }
        }
        // [A, black]: 2 frames = half of 1 frame of A.
        let mut scene = headlight_wall(24, 18);
        let mut pair = atlases[0].clone();
        let black: Vec<Vec<glam::Vec3>> = pair
            .images
            .iter()
            .map(|im| vec![glam::Vec3::ZERO; im.len()])
            .collect();
        pair.sequence = vec![pair.images.clone(), black];
        scene.luminaires[0].luminaire = pair;
        let render = |scene: &irad::scene::Scene, frames: u32| {
            render_lightfield(
                ctx,
                scene,
                LightfieldSettings {
                    spp: 32,
                    frames,
                    seed: 5,
                    pixels: PixelSampling::Centres,
                    ..Default::default()
                },
            )
            .image
        };
        let two = render(&scene, 2);
        scene.luminaires[0].luminaire.sequence.clear();
        let one = render(&scene, 1);
        let total: f64 = one.pixels.iter().map(|p| p[1] as f64).sum();
        assert!(total > 0.0, "the headlight lights nothing");
        for (k, (a, b)) in two.pixels.iter().zip(&one.pixels).enumerate() {
            for c in 0..3 {
                assert!(
                    (2.0 * a[c] - b[c]).abs() <= 1e-5 * b[c].abs() + 1e-12,
                    "pixel {k} channel {c}: 2 frames of [A, black] {} against 1 frame of A {}",
                    a[c],
                    b[c]
                );
            }
        }
    });
}

/// Thousands of samples of one image at a pixel are all drawn and counted: lavapipe breaks out
/// of an invocation's loops after 65535 iterations in all, silently, and 2240 samples per pixel
/// in one dispatch once came out at half the light. The near-field scene (24 x 18, 2 frames)
/// with K = K_max = 2048 against K = 64: the same mean within 2%, and every sample drawn.
#[test]
fn thousands_of_samples_per_image_are_not_cut_short() {
    use irad::methods::gbuffer::PixelSampling;
    use irad::methods::lightfield::LightfieldSettings;
    with_gpu(|ctx| {
        let scene = headlight_wall(24, 18);
        let render = |k: u32| {
            render_lightfield(
                ctx,
                &scene,
                LightfieldSettings {
                    spp: k,
                    k_max: k,
                    frames: 2,
                    seed: 3,
                    pixels: PixelSampling::Centres,
                    ..Default::default()
                },
            )
        };
        let (few, many) = (render(64), render(2048));
        let stat = |out: &irad::methods::RenderOutput, name: &str| {
            out.stats.iter().find(|s| s.0 == name).unwrap().1
        };
        let drawn = stat(&many, "luminaire_samples_per_pixel");
        let ratio = common::luminance_mean(&many.image) / common::luminance_mean(&few.image);
        eprintln!("K = 2048: {drawn:.0} samples per lit pixel, mean / K = 64's {ratio:.4}");
        assert!(drawn >= 2048.0, "{drawn} samples per lit pixel");
        assert!((ratio - 1.0).abs() < 0.02, "mean {ratio:.4} of K = 64's");
    });
}

/// The faceted headlight against an integral that shares no code with the GPU sampler: the
/// floor 0.8 below the scene's generated reflector light field (aimed down; the view off its
/// axis, where the beams land), the restricted strategy's 4 x 4 centre pixels (K = 256, 64
/// frames, 4 seeds) against the f64 mirror's integral over the filter plane at the same
/// points (96 x 96 per basis: 0.05% from 384 x 384), within 1%. This backs the suites, whose
/// reference for luminaire scenes is the restricted strategy itself.
#[test]
fn restricted_matches_the_f64_integral_on_the_faceted_headlight() {
    with_gpu(|ctx| {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("scenes/failure/headlight-wall/headlight/luminaire.toml");
        let luminaire = Luminaire::load(&path).unwrap();
        let mirror = LuminaireSampler::new(&luminaire);
        let mut scene = disk_over_floor(luminaire, 0.8, CENTRE_FOV, CENTRE_SIZE);
        // Look at the floor 0.25 off the axis toward the luminaire's -y (the beams go down).
        let spot = glam::Vec3::new(0.0, 0.0, 0.25);
        scene.camera.position = spot + glam::Vec3::new(0.0, 3.0, 0.0);
        scene.camera.look_at = spot;
        let pixels = centre_pixels(&scene);
        let expected = 0.5 / std::f64::consts::PI
            * pixels
                .iter()
                .map(|&(x, y)| {
                    let p = floor_point(&scene, x, y);
                    mirror.irradiance_over_filter_plane(p, 96, true)
                })
                .sum::<f64>()
            / pixels.len() as f64;
        assert!(expected > 0.0, "no light at the spot");
        let (mean, stderr) = centre_ratio(ctx, &scene, expected);
        eprintln!("faceted headlight: lightfield / integral over U {mean:.4} ± {stderr:.4}");
        assert!(stderr < 0.005, "standard error {stderr}");
        assert!((mean - 1.0).abs() < 0.01, "{mean:.4}");
    });
}
