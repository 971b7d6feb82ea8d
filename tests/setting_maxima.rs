//! Every count-like setting of every method (the `Kind::Count` rows of the settings tables) at
//! its documented maximum, one at a time, gives the image mean the method's default settings
//! give. lavapipe stops an invocation's loops silently after 65535 iterations in all
//! (docs/DESIGN.md "The loop budget"), so a kernel whose loop grows with a setting comes out
//! dark there, with exit 0: env's 16384 samples per pixel were 10% dark and 65536 up to 80%,
//! bir's 1024 light samples 8.5%.
//!
//! Noise model: each method's base image (its defaults, a few more frames where one frame is
//! noisy; `base`) at SEEDS seeds gives the image mean's spread s (the sample standard deviation
//! over seeds). A run at a maximum takes as many samples or more per frame, so its spread is
//! taken as at most s sqrt(F / F_run) for F_run frames against the base's F; it passes when it
//! lies within 5 s sqrt(F / F_run + 1 / SEEDS) of the seeds' mean (5: s comes from 8 seeds,
//! and Student's t with 7 degrees of freedom passes 5 with probability 0.2%). Every image is
//! rendered at pixel centres, so the spread is the estimator's own, not the pixel footprint's;
//! and every image is deterministic (same seed, same device, same bits), so a pass or a
//! failure repeats.
//!
//! Some maxima are too slow for a test on lavapipe; those run at the largest value that still
//! crosses the loop budget by a wide margin, and the table says why. Settings that no kernel
//! loop counts (frames and the reference's samples are frames on the host, a seed is no
//! count) are listed with the reason. A new `Kind::Count` setting fails the test until it has a
//! row here.

use crate::common;

use common::{luminance_mean, scene_file, with_gpu};
use irad::methods::settings::Kind;
use irad::methods::{Method, Registry, Renderers};
use irad::scene::gpu::GpuScene;

const SEEDS: u32 = 8;

/// What the test does with one setting.
enum Run {
    /// Render at `value` (TOML; `MAX`: the documented maximum), with `shared` settings on the
    /// base and the run alike and `run` settings on the run alone; `why` says why the value is
    /// not the maximum where it is not.
    At {
        value: &'static str,
        shared: &'static str,
        run: &'static str,
        why: &'static str,
    },
    /// Not rendered: why no kernel loop grows with it.
    Skip(&'static str),
}

const fn max() -> Run {
    Run::At {
        value: "MAX",
        shared: "",
        run: "",
        why: "",
    }
}

/// The maximum, on one frame (of a base of several).
const fn one_frame() -> Run {
    Run::At {
        value: "MAX",
        shared: "",
        run: "frames = 1",
        why: "",
    }
}

/// What to do with `method`'s setting `key`.
fn plan(method: &str, key: &str) -> Option<Run> {
    use Run::*;
    Some(match (method, key) {
        (_, "frames") => Skip("frames are submissions on the host, each with fresh loops"),
        (_, "seed") => Skip("a seed is no count of work"),
        (_, "direct_spp") => max(),
        ("reference", "spp") => Skip("the reference's samples are frames on the host"),
        ("reference", "max_depth") => max(),
        ("reference", "roulette_depth") => max(),
        ("reference", "alpha_frames") => {
            Skip("frames on the host; a frame of the split takes two samples per pixel")
        }
        ("ir", "vpls") => At {
            value: "16384",
            shared: "",
            run: "",
            why: "2^20 paths gather 2^21 VPLs per pixel, minutes on lavapipe; 16384 paths' \
                  ~30000 VPLs, a shadow ray each, would pass the budget 10 times over in one \
                  dispatch",
        },
        ("ir", "interleave") => max(),
        ("ir", "reuse") => Skip(
            "a still render walks every path; in a sequence reweigh_vpls.comp loops over at \
             most 16 classes (MAX_CLASSES, a shadow ray each) and the path's vertices, as the \
             walk does",
        ),
        ("bir", "vpls") => At {
            value: "4096",
            shared: "",
            run: "frames = 1",
            why: "2^20 VPLs connect each reverse VPL's paths to 2^19 slots, hours on lavapipe; \
                  at 4096 a reverse VPL's 4 paths connect to ~2000 slots each, 8000 shadow rays",
        },
        ("bir", "pool") => one_frame(),
        // Under `both` the reverse side's paths (the part the loop budget cut) are a few
        // percent of the image; alone, every candidate shaded, they are the indirect light
        // with little noise (the budget cut them 5.3% dark here), on the base's four frames.
        ("bir", "light_samples") => At {
            value: "MAX",
            shared: "strategy = \"reverse\"\nratio = 0",
            run: "",
            why: "",
        },
        ("bir", "connections") => max(),
        ("bir", "reverse_history") => Skip(
            "each earlier batch's set is dispatches of its own, split as the batch's own set's \
             connections are",
        ),
        ("bir", "depth") => max(),
        ("bir", "ratio") => Skip(
            "a larger ratio keeps fewer VPLs (one at the maximum): no loop grows, only the \
             noise; the resampling's search is log2(candidates) steps",
        ),
        ("bir", "power_samples") => max(),
        ("bir", "batch") => max(),
        ("bundles", "iterations") => At {
            value: "8192",
            shared: "",
            run: "frames = 1",
            why: "65536 iterations take half a minute at 16x16; 8192 in one 4096-iteration \
                  chunk would cast 16000 shadow rays per pixel in one dispatch",
        },
        ("env", "spp") => At {
            value: "MAX",
            shared: "",
            run: "frames = 1",
            why: "",
        },
        ("env", "face_resolution") => At {
            value: "1",
            shared: "",
            run: "",
            why: "more texels shorten the weighing loop (a cube texel covers fewer map \
                  texels), so its longest loop is at the minimum, run instead (the maximum \
                  builds 10^8 texels)",
        },
        ("env", "alpha_samples") => At {
            value: "MAX",
            shared: "strategy = \"alpha\"",
            run: "spp = 65536\nframes = 1",
            why: "",
        },
        // One frame: the candidates' loop (a light-BVH descent each) in one invocation.
        ("restir", "candidates") => one_frame(),
        ("restir", "bsdf_candidates") => one_frame(),
        // Every stream holding candidates of both kinds: the longest loops before the rays.
        ("restir", "candidate_shadow_rays") => At {
            value: "MAX",
            shared: "candidates = 512\nbsdf_candidates = 16",
            run: "frames = 1",
            why: "",
        },
        ("restir", "neighbours") => max(),
        ("restir", "radius") => Skip("a radius places the neighbours; no loop grows with it"),
        ("restir", "temporal_cap") => Skip("a cap on a reservoir's M: a weight, no loop counts it"),
        ("restir", "relit_cap") => {
            Skip("temporal_cap on a relit frame: a weight, no loop counts it")
        }
        ("lightfield", "spp") => max(),
        ("lightfield", "k_max") => At {
            value: "MAX",
            shared: "",
            run: "spp = 8192",
            why: "",
        },
        _ => return None,
    })
}

/// Each method's scene (one it renders) and its base settings: the defaults at pixel centres,
/// with as many frames (env: samples) as keep the image mean's spread near 1% in a test's
/// time.
fn base(method: &str) -> (&'static str, &'static str) {
    match method {
        "reference" => ("cornell-box", "spp = 16"),
        "ir" => ("cornell-box", "frames = 2"),
        "bir" => ("cornell-box", "frames = 4"),
        "bundles" => ("spot-light", "frames = 8"),
        "env" => ("glossy-env", "spp = 1024\nframes = 2"),
        "lightfield" => ("failure/headlight-wall", "frames = 1"),
        // Many lights (a deep tree) and a map: the candidates' loop at its longest.
        "restir" => ("many-lights-sky", "frames = 4"),
        _ => unreachable!("a method this test does not know: {method}"),
    }
}

/// `name` with the settings of `layers` (TOML texts), a later layer's key over an earlier's,
/// at pixel centres.
fn method(name: &str, layers: &[&str]) -> Method {
    let mut table = toml::Table::new();
    for text in layers.iter().copied().chain(["pixel_centres = true"]) {
        let layer: toml::Table = text.parse().unwrap_or_else(|e| panic!("{text}: {e}"));
        table.extend(layer);
    }
    Method::from_params(name, &table).unwrap_or_else(|e| panic!("{name}: {table}: {e}"))
}

/// The methods of each maxima test: two tests, so that the two test threads share the
/// work (one test of every method was the test suite's last minute, run alone).
const GROUPS: [&[&str]; 2] = [
    &["reference", "ir", "bir"],
    &["bundles", "env", "lightfield", "restir"],
];

#[test]
fn every_count_setting_has_a_plan_and_every_method_a_group() {
    // Every Count row has a plan (checked without a GPU).
    let mut missing = vec![];
    for name in Registry::builtin().names() {
        for doc in Method::settings(name).unwrap() {
            if matches!(doc.kind, Kind::Count { .. }) && plan(name, doc.key).is_none() {
                missing.push(format!("{name}.{}", doc.key));
            }
        }
    }
    assert!(missing.is_empty(), "no plan for {missing:?}");
    let mut grouped: Vec<&str> = GROUPS.concat();
    let mut names = Registry::builtin().names();
    grouped.sort();
    names.sort();
    assert_eq!(grouped, names, "every built-in method in one of GROUPS");
}

#[test]
fn counts_at_their_maximum_keep_the_image_mean_reference_ir_bir() {
    maxima_keep_the_image_mean(GROUPS[0]);
}

#[test]
fn counts_at_their_maximum_keep_the_image_mean_bundles_env_lightfield_restir() {
    maxima_keep_the_image_mean(GROUPS[1]);
}

/// Each Count setting of `names` at its maximum (or the plan's value) renders the image mean
/// of the default within the seeds' spread.
fn maxima_keep_the_image_mean(names: &[&str]) {
    with_gpu(|ctx| {
        let renderers = Renderers::default();
        let mut failures = vec![];
        for &name in names {
            let (scene_name, base_params) = base(name);
            let scene = scene_file(scene_name, 16, 16);
            let gpu_scene = GpuScene::upload(ctx, &scene).unwrap();
            let render = |layers: &[&str], seed: u32| -> f64 {
                let seed = format!("seed = {seed}");
                let mut all = vec![base_params, seed.as_str()];
                all.extend(layers);
                let m = method(name, &all);
                let out = renderers
                    .run(ctx, &m, &scene, &gpu_scene, |_, _| {})
                    .unwrap_or_else(|e| panic!("{name} {layers:?}: {e}"));
                luminance_mean(&out.image)
            };
            let mut bases: std::collections::BTreeMap<&str, (f64, f64)> = Default::default();
            let mut base_for = |extra: &'static str| -> (f64, f64) {
                *bases.entry(extra).or_insert_with(|| {
                    let means: Vec<f64> = (0..SEEDS).map(|s| render(&[extra], s)).collect();
                    let (mean, _) = common::mean_and_stderr(&means);
                    let spread = (means.iter().map(|m| (m - mean).powi(2)).sum::<f64>()
                        / (SEEDS - 1) as f64)
                        .sqrt();
                    (mean, spread)
                })
            };
            for doc in Method::settings(name).unwrap() {
                let Kind::Count { max, .. } = doc.kind else {
                    continue;
                };
                let (value, shared, run, why) = match plan(name, doc.key) {
                    Some(Run::At {
                        value,
                        shared,
                        run,
                        why,
                    }) => (value, shared, run, why),
                    Some(Run::Skip(why)) => {
                        eprintln!("{name} {}: not rendered [{why}]", doc.key);
                        continue;
                    }
                    None => unreachable!("checked above"),
                };
                let value = if value == "MAX" {
                    max.to_string()
                } else {
                    value.to_string()
                };
                let (mean, spread) = base_for(shared);
                let start = std::time::Instant::now();
                let setting = format!("{} = {value}", doc.key);
                let got = render(&[shared, run, &setting], 100);
                let frames = |layers: &[&str]| -> f64 {
                    let m = method(name, layers);
                    m.samples() as f64
                };
                let base_frames = frames(&[base_params, shared]);
                let run_frames = frames(&[base_params, shared, run, &setting]);
                let tolerance =
                    5.0 * spread * (base_frames / run_frames + 1.0 / SEEDS as f64).sqrt();
                let ratio = got / mean;
                eprintln!(
                    "{name} {} = {value}: mean {got:.5} against {mean:.5} +- {spread:.5} ({ratio:.4}; {:.1} s){}",
                    doc.key,
                    start.elapsed().as_secs_f64(),
                    if why.is_empty() { String::new() } else { format!(" [{why}]") }
                );
                if (got - mean).abs() > tolerance {
                    failures.push(format!(
                        "{name} --{} {value}: image mean {got:.5}, {ratio:.4} of the default's {mean:.5} (tolerance {tolerance:.5})",
                        doc.key.replace('_', "-")
                    ));
                }
            }
        }
        assert!(failures.is_empty(), "{}", failures.join("\n"));
    });
}
