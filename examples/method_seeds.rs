//! Any method across many seeds on one scene: the image mean against the reference's, relMSE
//! against a split reference, GPU time and the method's stats, averaged over seeds: how the
//! many-seed figures of docs/RESULTS.md and docs/methods/ were measured (bir's U office means,
//! bundles' environment checks, env's equal-error ratios).
//!
//!   cargo run --release --example method_seeds -- SCENE.toml WIDTHxHEIGHT SEEDS REF_SPP \
//!       REF_DEPTH "bir:strategy=both,vpls=256,frames=8" "bundles:directions=uniform" ...
//!
//! The reference is two path-traced renders of REF_SPP samples each (seeds 77 and 78) with at
//! most REF_DEPTH scattering events (1: direct light; 1024: all), at pixel centres when a
//! configuration asks for `pixel_centres=true`, cached as out/method_seeds/
//! SCENE_ref_{77,78}_WxH_SPP_dDEPTH[_centres]_HASH.exr (HASH: of the scene file's
//! text). Each configuration is METHOD:PARAMS, PARAMS comma-separated key=value pairs as in suite files (Method::from_params: numbers,
//! true/false, or bare words for choices); it renders with seeds 1000.. and prints the image
//! mean relative to the reference's (mean and standard error over seeds), relMSE against the
//! split reference (metrics::rel_mse_against_split_reference: the references' own noise taken
//! out) as mean, median and max over seeds, and the method's stats averaged. Unclamped VPLs have
//! an infinite-variance per-pixel estimator wherever a VPL can land arbitrarily close to a
//! visible surface, so the mean of relMSE over seeds is dominated by its largest seed and the
//! median is the stable figure of a typical render. METHOD_SEEDS_VERBOSE=1 also prints every
//! seed's image mean (relative to the reference's), to tell a heavy tail from a broad spread.

use std::path::{Path, PathBuf};

use irad::gpu::{Context, ContextOptions, Validation};
use irad::image::{exr, metrics, Image};
use irad::methods::gbuffer::PixelSampling;
use irad::methods::reference::{Reference, ReferenceSettings};
use irad::methods::{Method, Renderer, Renderers, RunError};
use irad::scene::gpu::GpuScene;
use irad::scene::Scene;

fn luminance_mean(image: &Image) -> f64 {
    metrics::luminance(image.mean().map(f64::from))
}

fn mean_and_stderr(values: &[f64]) -> (f64, f64) {
    let n = values.len() as f64;
    let mean = values.iter().sum::<f64>() / n;
    let var = values.iter().map(|m| (m - mean).powi(2)).sum::<f64>() / (n - 1.0).max(1.0);
    (mean, (var / n).sqrt())
}

/// METHOD:key=value,... as a Method.
fn method(config: &str) -> Result<Method, String> {
    let (name, params) = config.split_once(':').unwrap_or((config, ""));
    let mut table = toml::Table::new();
    for kv in params.split(',').filter(|kv| !kv.is_empty()) {
        let (key, value) = kv
            .split_once('=')
            .ok_or_else(|| format!("`{kv}` in `{config}` is not key=value"))?;
        let parsed = format!("v = {value}")
            .parse::<toml::Table>()
            .ok()
            .and_then(|mut t| t.remove("v"))
            .unwrap_or_else(|| toml::Value::String(value.to_string()));
        table.insert(key.to_string(), parsed);
    }
    Method::from_params(name, &table).map_err(|e| e.to_string())
}

#[allow(clippy::too_many_arguments)]
fn reference(
    ctx: &Context,
    scene: &Scene,
    gpu: &GpuScene,
    path: &Path,
    spp: u32,
    max_depth: u32,
    pixels: PixelSampling,
    seed: u32,
) -> Image {
    if let Ok(image) = exr::read(path) {
        return image;
    }
    eprintln!("rendering {} ({spp} spp)", path.display());
    let settings = ReferenceSettings {
        spp,
        seed,
        max_depth,
        pixels,
        ..Default::default()
    };
    let out = Renderer::<Reference>::new(ctx)
        .map_err(RunError::from)
        .and_then(|r| r.render(ctx, scene, gpu, &settings, |_, _| {}))
        .unwrap_or_else(|e| panic!("reference: {e}"));
    exr::write(path, &out.image).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    out.image
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    if args.len() < 6 {
        eprintln!(
            "usage: method_seeds SCENE.toml WIDTHxHEIGHT SEEDS REF_SPP REF_DEPTH METHOD:PARAMS..."
        );
        std::process::exit(2);
    }
    let scene_path = PathBuf::from(&args[0]);
    let (width, height) = args[1]
        .split_once('x')
        .and_then(|(w, h)| Some((w.parse::<u32>().ok()?, h.parse::<u32>().ok()?)))
        .unwrap_or_else(|| panic!("size `{}`: expected WIDTHxHEIGHT", args[1]));
    let seeds: u32 = args[2]
        .parse()
        .ok()
        .filter(|&n| n > 0)
        .unwrap_or_else(|| panic!("SEEDS `{}`: expected a count of at least 1", args[2]));
    let ref_spp: u32 = args[3].parse().expect("REF_SPP: samples per pixel");
    let ref_depth: u32 = args[4].parse().expect("REF_DEPTH: most scattering events");
    let configs: Vec<(String, Method)> = args[5..]
        .iter()
        .map(|c| (c.clone(), method(c).unwrap_or_else(|e| panic!("{e}"))))
        .collect();
    let centres = configs
        .iter()
        .any(|(_, m)| m.parameters().get("pixel_centres") == Some(&serde_json::json!(true)));
    let pixels = if centres {
        PixelSampling::Centres
    } else {
        PixelSampling::Jittered
    };

    let ctx = Context::new(&ContextOptions {
        device: None,
        validation: Validation::Off,
        force_staging: false,
    })
    .expect("a Vulkan device");
    let mut scene = irad::scene::load(&scene_path).unwrap_or_else(|e| panic!("{e}"));
    scene.camera.width = width;
    scene.camera.height = height;
    let gpu = GpuScene::upload(&ctx, &scene).expect("scene upload");
    // Keyed by the scene file's text too, so an edited scene never reuses a stale reference.
    let text = std::fs::read(&scene_path).unwrap_or_default();
    let key = text.iter().fold(0xcbf29ce484222325u64, |h, &b| {
        (h ^ b as u64).wrapping_mul(0x100000001b3)
    });
    // Under out/, never beside the scene: a cache is no part of the scene's folder.
    let folder = std::path::Path::new("out").join("method_seeds");
    std::fs::create_dir_all(&folder).expect("creating out/method_seeds");
    let cache = |seed: u32| {
        folder.join(format!(
            "{}_ref_{seed}_{width}x{height}_{ref_spp}_d{ref_depth}{}_{key:016x}.exr",
            irad::bench::suite::file::file_safe(&scene.name),
            if centres { "_centres" } else { "" }
        ))
    };
    let a = reference(
        &ctx,
        &scene,
        &gpu,
        &cache(77),
        ref_spp,
        ref_depth,
        pixels,
        77,
    );
    let b = reference(
        &ctx,
        &scene,
        &gpu,
        &cache(78),
        ref_spp,
        ref_depth,
        pixels,
        78,
    );
    let own = metrics::compare(&a, &b).unwrap().rel_mse / 4.0;
    let mut r = a.clone();
    for (p, q) in r.pixels.iter_mut().zip(&b.pixels) {
        for c in 0..3 {
            p[c] = 0.5 * (p[c] + q[c]);
        }
    }
    let r_mean = luminance_mean(&r);
    if std::env::var_os("METHOD_SEEDS_VERBOSE").is_some() {
        println!(
            "reference halves' means {:.4} {:.4}",
            luminance_mean(&a) / r_mean,
            luminance_mean(&b) / r_mean
        );
    }
    let black = Image {
        width,
        height,
        pixels: vec![[0.0; 3]; (width * height) as usize],
    };
    println!(
        "{}, {width}x{height}, {seeds} seeds; reference 2 x {ref_spp} spp, luminance mean {r_mean:.4}, own relMSE about {own:.2e}; a black image scores {:.3}",
        scene_path.display(),
        metrics::rel_mse_against_split_reference(&black, &a, &b).unwrap()
    );
    let renderers = Renderers::default();
    for (name, base) in &configs {
        let (mut means, mut errors, mut gpu_ms) = (vec![], vec![], 0.0);
        let mut stats: Vec<(String, f64)> = vec![];
        for seed in 0..seeds {
            let out = renderers
                .run(&ctx, &base.with_seed(1000 + seed), &scene, &gpu, |_, _| {})
                .unwrap_or_else(|e| panic!("{name}: {e}"));
            means.push(luminance_mean(&out.image) / r_mean);
            errors.push(metrics::rel_mse_against_split_reference(&out.image, &a, &b).unwrap());
            gpu_ms += out.passes.total_gpu_ms().unwrap_or(0.0) / seeds as f64;
            for (k, v) in &out.stats {
                match stats.iter_mut().find(|(n, _)| n == k) {
                    Some(e) => e.1 += v / seeds as f64,
                    None => stats.push((k.clone(), v / seeds as f64)),
                }
            }
        }
        let (m, e) = mean_and_stderr(&means);
        if std::env::var_os("METHOD_SEEDS_VERBOSE").is_some() {
            let list: Vec<String> = means.iter().map(|m| format!("{m:.3}")).collect();
            println!("{name}: per-seed means {}", list.join(" "));
        }
        let mut sorted = errors.clone();
        sorted.sort_by(f64::total_cmp);
        let stats: Vec<String> = stats.iter().map(|(k, v)| format!("{k} {v:.3}")).collect();
        println!(
            "{name}: mean {m:.4} ± {e:.4}; relMSE mean {:.3e} median {:.3e} max {:.3e}; {gpu_ms:.0} GPU ms per render; {}",
            errors.iter().sum::<f64>() / errors.len() as f64,
            sorted[sorted.len() / 2],
            sorted[sorted.len() - 1],
            stats.join(", ")
        );
    }
}
