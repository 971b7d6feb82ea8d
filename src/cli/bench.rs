//! `irad bench`: the benchmarks that measure and print (the suite runner is in suite.rs).

use std::path::PathBuf;

use anyhow::Result;
use clap::Subcommand;

use irad::bench::scan as scan_bench;
use irad::gpu::{Context, ContextOptions};
use irad::methods::envmap::Strategy as EnvStrategy;
use irad::methods::lightfield::Strategy as LightfieldStrategy;
use irad::render;
use irad::scene;

use super::{device_line, parse_size, progress};

#[derive(Subcommand)]
pub enum Bench {
    /// Prefix-sum GB/s next to a plain copy kernel's GB/s (the bandwidth bound), per size.
    Scan {
        /// Timed repetitions per size (the median is reported), after 3 warm-up runs.
        #[arg(long, default_value_t = 15)]
        repeats: usize,
        /// Sizes as ROW_LENGTH or ROW_LENGTHxROWS, comma separated (default: a set from 2^16
        /// to 6 x 2^20 elements, single rows and batched rows). Elements must be a multiple of 4.
        #[arg(long, value_delimiter = ',', value_parser = parse_case)]
        sizes: Vec<scan_bench::ScanCase>,
    },
    /// env's per-frame sampling table (cube map, CDFs, light samples) at several cube-face
    /// resolutions, next to the time to copy the map once (the bandwidth bound) and the
    /// latitude-longitude table's build.
    Env {
        /// Scene file with an environment map (default: scenes/glossy-env of the source tree).
        scene: Option<PathBuf>,
        /// Replace the scene's map by a synthetic sky of this size, WIDTHxHEIGHT (the work
        /// depends on the map's size, not its content).
        #[arg(long, value_parser = parse_size)]
        map: Option<(u32, u32)>,
        /// Cube-face resolutions, comma separated.
        #[arg(long, value_delimiter = ',', default_values_t = [64u32, 128, 256, 512, 1024])]
        faces: Vec<u32>,
        /// Light samples per face (N_s / 2).
        #[arg(long, default_value_t = 30)]
        samples: u32,
        /// Timed repetitions per resolution (the median is reported), after 2 warm-up runs.
        #[arg(long, default_value_t = 9)]
        repeats: usize,
        /// Then the shading table: env's frame time at these samples per pixel (N_s), with
        /// and without shadow rays, comma separated; 0 skips it.
        #[arg(long, value_delimiter = ',', default_values_t = [16u32, 60, 240])]
        spp: Vec<u32>,
        /// The strategies of the shading table, comma separated.
        #[arg(long, value_delimiter = ',', default_values_t = ["dynamic".to_string(), "alpha".into(), "latlong".into(), "hierarchical".into()])]
        strategies: Vec<String>,
        /// The shading table's image size, WIDTHxHEIGHT (default: the scene's).
        #[arg(long, value_parser = parse_size)]
        resolution: Option<(u32, u32)>,
        /// The shading table's timed frames per row (after one warm-up frame).
        #[arg(long, default_value_t = 4, value_parser = clap::value_parser!(u32).range(1..))]
        frames: u32,
    },
    /// lightfield's per-frame breakdown (Lu 14 Fig. 4.12: G-buffer, A estimation, sampling,
    /// shading, shadow rays) for each strategy and sample budget K, with the frame rate and
    /// the samples actually drawn per lit pixel. Time against error: `irad bench suite
    /// scenes/suites/lightfield-lavapipe.toml` (or lightfield.toml on a GPU).
    Lightfield {
        /// Scene file with luminaires (default: scenes/car-headlights of the source tree, the
        /// thesis's two-headlight car).
        scene: Option<PathBuf>,
        /// K, samples per pixel, luminaire and frame, comma separated (the thesis: 200).
        #[arg(long, value_delimiter = ',', default_values_t = [50u32, 100, 200])]
        spp: Vec<u32>,
        /// The strategies, comma separated.
        #[arg(long, value_delimiter = ',', default_values_t = ["restricted".to_string(), "uniform".into(), "precomputed".into()])]
        strategies: Vec<String>,
        /// K_max, the most samples per pixel, frame and image.
        #[arg(long, default_value_t = 64, value_parser = clap::value_parser!(u32).range(1..=65536))]
        k_max: u32,
        /// Image size, WIDTHxHEIGHT (default: the scene's; the thesis: 1024x768).
        #[arg(long, value_parser = parse_size)]
        resolution: Option<(u32, u32)>,
        /// Timed frames per render (after a one-frame warm-up).
        #[arg(long, default_value_t = 4, value_parser = clap::value_parser!(u32).range(1..))]
        frames: u32,
        /// Timed renders of each kind (the median is reported).
        #[arg(long, default_value_t = 3, value_parser = clap::value_parser!(u32).range(1..))]
        repeats: u32,
    },
    /// Instant radiosity's per-pass GPU times for a range of VPL budgets, and its gathering
    /// throughput in (pixel, VPL) pairs/s next to the scene's incoherent any-hit ray rate.
    Ir {
        /// Scene file (default: the embedded Cornell box).
        scene: Option<PathBuf>,
        /// Paths per frame (Keller's N), comma separated.
        #[arg(long, value_delimiter = ',', default_values_t = [64u32, 256, 1024, 4096])]
        vpls: Vec<u32>,
        /// Frames rendered per budget (the mean per frame is reported), after a warm-up.
        #[arg(long, default_value_t = 3, value_parser = clap::value_parser!(u32).range(1..))]
        frames: u32,
        /// Interleaved sampling k.
        #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..=16))]
        interleave: u32,
        /// Random rays for the any-hit ray rate.
        #[arg(long, default_value_t = 1 << 18)]
        rays: usize,
    },
    /// Run a benchmark suite: every method at every budget on every scene, timed (median of
    /// repeats after a warm-up) and scored against each scene's cached reference. Writes
    /// results.csv, results.json, charts/<scene>.svg (relMSE against GPU time, log-log) and
    /// report.md (tables, Pareto-optimal runs, thumbnails and error maps) into the output
    /// folder, rewritten after every run, so an interrupted suite leaves readable results.
    Suite(super::suite::SuiteArgs),
    /// Render or extend the converged references of a suite's scenes: rendered once, in
    /// chunks, to a net relMSE of at most 0.01 (judged by split halves), and stored in the
    /// repository beside each scene (<scene folder>/converged/), where the suite finds them
    /// in place of its cached references when the scene and reference settings match. An
    /// animated scene gets one per frame of the suite's `frames`; --shard I/N takes frames
    /// f mod N = I. Resumable: stop it any time (Ctrl-C, --minutes) and the same command goes on.
    References(super::references::ReferencesArgs),
    /// Merge the output folders of a suite's shards into one set of results, charts and report.
    Merge {
        /// Output folders of `irad bench suite --shard`.
        #[arg(required = true)]
        parts: Vec<PathBuf>,
        /// Merged output folder.
        #[arg(short, long, value_name = "DIR")]
        out: PathBuf,
        /// Merge parts measured on different devices, drivers or irad versions (refused by
        /// default: their GPU times are not comparable). Charts then get a line per method
        /// and device, and Pareto marks are per device.
        #[arg(long)]
        allow_mixed_devices: bool,
    },
    /// Rays/s of the GPU BVH traversal (closest and any hit; camera and random rays) next to
    /// obvhs's CWBVH on the CPU using every core, and the ratio GPU/CPU.
    Rays {
        /// Scene file: its triangles, its camera at 1024x768 (default: a displaced sphere of
        /// 196608 triangles and 1024 random ones).
        scene: Option<std::path::PathBuf>,
        /// Timed repetitions per case (the median is reported), after 1 warm-up run.
        #[arg(long, default_value_t = 5)]
        repeats: usize,
        /// Number of random (incoherent) rays; camera rays are one per pixel of 1024x768.
        #[arg(long, default_value_t = 1 << 20)]
        rays: usize,
    },
}

fn parse_case(s: &str) -> Result<scan_bench::ScanCase, String> {
    let parse = |t: &str| {
        t.trim()
            .parse::<usize>()
            .map_err(|_| format!("`{s}`: expected ROW_LENGTH or ROW_LENGTHxROWS"))
    };
    let (row_length, row_count) = match s.split_once('x') {
        Some((l, r)) => (parse(l)?, parse(r)?),
        None => (parse(s)?, 1),
    };
    if row_length == 0 || row_count == 0 {
        return Err(format!("`{s}`: sizes must be positive"));
    }
    if row_length
        .checked_mul(row_count)
        .is_none_or(|n| n > u32::MAX as usize)
    {
        return Err(format!("`{s}`: more elements than a u32 can index"));
    }
    Ok(scan_bench::ScanCase {
        row_length,
        row_count,
    })
}

/// Runs one benchmark.
pub fn run(options: &ContextOptions, bench: Bench) -> Result<()> {
    match bench {
        Bench::Scan { repeats, sizes } => run_scan(options, repeats, sizes),
        Bench::Env {
            scene,
            map,
            faces,
            samples,
            repeats,
            spp,
            strategies,
            resolution,
            frames,
        } => {
            let (ctx, scene) = run_env_tables(options, scene, map, &faces, samples, repeats)?;
            run_env_shading(&ctx, scene, spp, &strategies, resolution, frames)
        }
        Bench::Ir {
            scene,
            vpls,
            frames,
            interleave,
            rays,
        } => run_ir(options, scene, &vpls, frames, interleave, rays),
        Bench::Lightfield {
            scene,
            spp,
            strategies,
            k_max,
            resolution,
            frames,
            repeats,
        } => {
            let scene = lightfield_scene(scene, resolution)?;
            run_lightfield(options, &scene, &spp, &strategies, k_max, frames, repeats)
        }
        Bench::Suite(args) => super::suite::run(options, args),
        Bench::References(args) => super::references::run(options, args),
        Bench::Merge {
            parts,
            out,
            allow_mixed_devices,
        } => run_merge(&parts, &out, allow_mixed_devices),
        Bench::Rays {
            scene,
            repeats,
            rays,
        } => run_rays(options, scene, repeats, rays),
    }
}

/// `bench scan`: times each size (the defaults when none is given) and prints the table.
fn run_scan(
    options: &ContextOptions,
    repeats: usize,
    sizes: Vec<scan_bench::ScanCase>,
) -> Result<()> {
    let ctx = Context::new(options)?;
    let cases = if sizes.is_empty() {
        scan_bench::DEFAULT_CASES.to_vec()
    } else {
        sizes
    };
    let bar = progress(cases.len() as u64, "bench scan");
    let mut results = Vec::new();
    for case in cases {
        bar.set_message(format!("{} x {}", case.row_length, case.row_count));
        results.push(scan_bench::run_case(&ctx, case, 3, repeats.max(1))?);
        bar.inc(1);
    }
    bar.finish_and_clear();
    scan_bench::print_table(&device_line(ctx.info()), &results);
    Ok(())
}

/// `bench env`, first step: loads the scene (with `--map`'s synthetic sky), times the
/// sampling table at each face resolution and prints it; returns the context and the scene
/// for the shading table.
fn run_env_tables(
    options: &ContextOptions,
    scene: Option<PathBuf>,
    map: Option<(u32, u32)>,
    faces: &[u32],
    samples: u32,
    repeats: usize,
) -> Result<(Context, scene::Scene)> {
    let path = scene.unwrap_or_else(|| {
        PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("scenes/glossy-env/scene.toml")
    });
    let mut scene = scene::load(&path)?;
    if let Some((w, h)) = map {
        scene.environment = Some(irad::bench::env::synthetic_sky(w, h));
    }
    anyhow::ensure!(
        faces.iter().all(|&r| (1..=4096).contains(&r)),
        "--faces: each resolution must be in 1..=4096"
    );
    let ctx = Context::new(options)?;
    let bar = progress(faces.len() as u64, "bench env");
    let results = irad::bench::env::run(
        &ctx,
        &scene,
        faces,
        samples.max(1),
        2,
        repeats.max(1),
        |r| {
            bar.set_message(format!("R = {r}"));
            bar.inc(1);
        },
    )?;
    bar.finish_and_clear();
    let map = scene.environment.as_ref().expect("checked by run");
    irad::bench::env::print_table(&device_line(ctx.info()), map, samples.max(1), &results);
    Ok((ctx, scene))
}

/// `bench env`, second step: the shading table, env's frame time per strategy and N_s with
/// and without shadow rays (nothing when every `--spp` is 0).
fn run_env_shading(
    ctx: &Context,
    mut scene: scene::Scene,
    spp: Vec<u32>,
    strategies: &[String],
    resolution: Option<(u32, u32)>,
    frames: u32,
) -> Result<()> {
    let spp: Vec<u32> = spp.into_iter().filter(|&n| n > 0).collect();
    if spp.is_empty() {
        return Ok(());
    }
    let strategies = strategies_by_name(strategies, &EnvStrategy::ALL, |s| s.name(), "env")?;
    if let Some((w, h)) = resolution {
        scene.camera.width = w;
        scene.camera.height = h;
    }
    let bar = progress(
        (strategies.len() * spp.len() * 2) as u64,
        "bench env shading",
    );
    let face_resolution = 256;
    let shading = irad::bench::env::run_shading(
        ctx,
        &scene,
        &strategies,
        &spp,
        face_resolution,
        frames,
        |s, n, shadows| {
            bar.set_message(format!(
                "{} N_s {n}{}",
                s.name(),
                if shadows { "" } else { " no shadows" }
            ));
            bar.inc(1);
        },
    )?;
    bar.finish_and_clear();
    println!();
    irad::bench::env::print_shading(&device_line(ctx.info()), &scene, &shading);
    Ok(())
}

/// `bench ir`: instant radiosity's per-pass times per VPL budget and the any-hit ray rate.
fn run_ir(
    options: &ContextOptions,
    scene: Option<PathBuf>,
    vpls: &[u32],
    frames: u32,
    interleave: u32,
    rays: usize,
) -> Result<()> {
    let scene = match scene {
        Some(path) => scene::load(&path)?,
        None => scene::default_scene(),
    };
    let ctx = Context::new(options)?;
    let bar = progress(vpls.len() as u64 + 2, "bench ir");
    let report = irad::bench::ir::run(&ctx, &scene, vpls, frames, interleave, rays, |what| {
        bar.set_message(what.to_string());
        bar.inc(1);
    })?;
    bar.finish_and_clear();
    irad::bench::ir::print_table(
        &device_line(ctx.info()),
        &render::scene_label(&scene),
        scene.camera.width,
        scene.camera.height,
        &report,
    );
    Ok(())
}

/// `bench lightfield`, first step: loads the scene (default: the car headlights) at
/// `--resolution`.
fn lightfield_scene(
    scene: Option<PathBuf>,
    resolution: Option<(u32, u32)>,
) -> Result<scene::Scene> {
    let path = scene.unwrap_or_else(|| {
        PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("scenes/car-headlights/scene.toml")
    });
    let mut scene = scene::load(&path)?;
    if let Some((w, h)) = resolution {
        scene.camera.width = w;
        scene.camera.height = h;
    }
    Ok(scene)
}

/// `bench lightfield`, second step: checks `--spp` and `--strategies`, times each strategy
/// at each K and prints the breakdown.
fn run_lightfield(
    options: &ContextOptions,
    scene: &scene::Scene,
    spp: &[u32],
    strategies: &[String],
    k_max: u32,
    frames: u32,
    repeats: u32,
) -> Result<()> {
    anyhow::ensure!(
        !spp.is_empty() && spp.iter().all(|&k| (1..=65536).contains(&k)),
        "--spp: each K must be in 1..=65536"
    );
    let strategies = strategies_by_name(
        strategies,
        &LightfieldStrategy::ALL,
        |s| s.name(),
        "lightfield",
    )?;
    let ctx = Context::new(options)?;
    let bar = progress((strategies.len() * spp.len()) as u64, "bench lightfield");
    let results = irad::bench::lightfield::run(
        &ctx,
        scene,
        &strategies,
        spp,
        k_max,
        frames,
        repeats as usize,
        |s, k| {
            bar.set_message(format!("{} K {k}", s.name()));
            bar.inc(1);
        },
    )?;
    bar.finish_and_clear();
    irad::bench::lightfield::print(&device_line(ctx.info()), scene, k_max, frames, &results);
    Ok(())
}

/// `bench merge`: merges shard folders into `out` and says what it wrote.
fn run_merge(parts: &[PathBuf], out: &std::path::Path, allow_mixed_devices: bool) -> Result<()> {
    let merged = irad::bench::suite::merge::merge(parts, out, allow_mixed_devices)?;
    println!(
        "merged {} parts: {} of {} runs of suite {}{}",
        parts.len(),
        merged.runs.len(),
        merged.runs_in_suite,
        merged.suite,
        if merged.complete {
            ""
        } else {
            " (incomplete: some runs are missing)"
        }
    );
    println!("wrote {}", out.join("report.md").display());
    Ok(())
}

/// `bench rays`: GPU and CPU BVH traversal rates on a scene's triangles or a procedural mesh.
fn run_rays(
    options: &ContextOptions,
    scene: Option<PathBuf>,
    repeats: usize,
    rays: usize,
) -> Result<()> {
    use irad::bvh::procedural;
    // A scene's own camera at 1024x768, or a camera framing the procedural mesh.
    let (triangles, camera) = match scene {
        Some(path) => {
            let scene = scene::load(&path)?;
            let triangles: Vec<_> = scene.triangles.iter().map(|t| t.positions).collect();
            let camera = irad::scene::Camera {
                width: 1024,
                height: 768,
                ..scene.camera
            };
            (triangles, camera)
        }
        None => {
            let triangles = procedural::noisy_sphere(1, 128, 1024);
            let camera = procedural::camera_for_bounds(procedural::bounds(&triangles), 1024, 768);
            (triangles, camera)
        }
    };
    let bounds = procedural::bounds(&triangles);
    let ctx = Context::new(options)?;
    let camera_rays = procedural::camera_rays(&camera);
    let random_rays = procedural::random_rays(2, bounds, rays);
    let report = irad::bench::rays::run(&ctx, &triangles, &camera_rays, &random_rays, repeats)?;
    irad::bench::rays::print_table(&device_line(ctx.info()), &report);
    Ok(())
}

/// `--strategies` of a bench: each name one of `all`'s, or an error listing them.
fn strategies_by_name<S: Copy>(
    names: &[String],
    all: &[S],
    name: impl Fn(S) -> &'static str,
    method: &str,
) -> Result<Vec<S>> {
    names
        .iter()
        .map(|wanted| {
            all.iter()
                .copied()
                .find(|&s| name(s) == wanted)
                .ok_or_else(|| {
                    let names: Vec<&str> = all.iter().map(|&s| name(s)).collect();
                    anyhow::anyhow!(
                        "--strategies: no {method} strategy {wanted:?} (one of {})",
                        names.join(", ")
                    )
                })
        })
        .collect()
}
