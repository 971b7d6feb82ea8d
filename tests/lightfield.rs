//! Light-field luminaires (issue 9, in progress): the GPU sampling tables against the f64
//! mirror.

mod common;

use irad::gpu::Commands;
use irad::methods::lightfield::tables::LuminaireTables;
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
/// reported pdf matches the mirror's at its texel (or it lies within 1e-3 texel of a texel
/// edge, where f32 may pick the neighbour), draws stay in the window, the histogram over the
/// texels passes a chi-square test, and the secant search takes fewer steps than binary search.
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
                    assert!(
                        (d[2] as f64 - p).abs() <= 1e-3 * p || edge(s) || edge(t),
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

/// Every strategy of `lightfield` against the brute force (uniform over each whole image, the
/// reference): on the near-field headlight scene (32 x 24, 8 frames, K = 64 and K_max = 64), the
/// image mean over 8 seeds within 1% of the brute force's (8 seeds of 2240 samples per pixel
/// and frame, standard error 0.3%), restricted also with Halton samples shared by every pixel;
/// the other methods decline the scene.
#[test]
fn every_lightfield_strategy_matches_the_brute_force() {
    use irad::methods::gbuffer::PixelSampling;
    use irad::methods::lightfield::{Lightfield, LightfieldSettings, Strategy};
    use irad::scene::gpu::GpuScene;
    with_gpu(|ctx| {
        let scene = headlight_wall(32, 24);
        let gpu = GpuScene::upload(ctx, &scene).unwrap();
        let lf = Lightfield::new(ctx).unwrap();
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
        let brute: Vec<f64> = (0..8)
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
                    " (shared Halton samples)"
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
        let reference = irad::methods::Method::Reference(Default::default());
        let why = reference.declines(&scene).unwrap();
        assert!(
            why.contains("does not render light-field luminaires"),
            "{why}"
        );
    });
}

/// Lu 14 Fig. 4.13-4.14 at equal samples on the near-field headlight scene (48 x 36, K = 64,
/// 4 frames, 4 seeds): the relMSE of each strategy against a split reference (restricted at
/// K = 1024, 8 frames, two seeds). Restricted has the lowest error, and uniform at 3x the
/// samples still has more (the issue: uniform needs at least 3x at equal error); the ratios are
/// printed.
#[test]
fn restricted_sampling_has_the_lowest_error_at_equal_samples() {
    use irad::image::metrics;
    use irad::methods::gbuffer::PixelSampling;
    use irad::methods::lightfield::{Lightfield, LightfieldSettings, Strategy};
    use irad::scene::gpu::GpuScene;
    with_gpu(|ctx| {
        let scene = headlight_wall(48, 36);
        let gpu = GpuScene::upload(ctx, &scene).unwrap();
        let lf = Lightfield::new(ctx).unwrap();
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
        let uniform = error(Strategy::Uniform, 64);
        let uniform3 = error(Strategy::Uniform, 192);
        let precomputed = error(Strategy::Precomputed, 64);
        eprintln!(
            "relMSE at K = 64: restricted {restricted:.3e}, uniform {uniform:.3e} ({:.1}x; at 3x the samples {uniform3:.3e}), precomputed {precomputed:.3e} ({:.1}x)",
            uniform / restricted,
            precomputed / restricted
        );
        // Restricted is best; uniform needs more than 3x its samples for its error (the
        // issue's figure; the thesis: 4x). Precomputed's gap depends on how much of each
        // image lies outside the windows (here 2.1x, the issue asks 10x: see the closing note).
        assert!(restricted < uniform && restricted < precomputed);
        assert!(
            uniform3 > restricted,
            "uniform at 3x: {uniform3:.3e} against {restricted:.3e}"
        );
    });
}
