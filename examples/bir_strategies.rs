//! bir's strategies across many seeds on one scene: the figures behind issue 6's U office
//! comparison (standard-only against `both` and reverse-only at an equal VPL budget).
//!
//!   cargo run --release --example bir_strategies -- SCENE.toml WIDTHxHEIGHT SEEDS REF_SPP \
//!       "strategy=both,vpls=256,frames=8" "strategy=standard,vpls=26,frames=8,ratio=0" ...
//!
//! The reference is two path-traced renders of REF_SPP samples each (seeds 77 and 78), cached
//! next to the scene as bir_strategies_ref_{77,78}_WxH_SPP.exr. Each configuration (comma-
//! separated `key=value` over BirSettings: strategy, vpls, frames, ratio, floor, pool,
//! power_samples, light_samples, depth, connections, batch, adaptive) renders with seeds
//! 1000.. and prints the image mean relative to the reference's (mean and standard error over
//! seeds), relMSE against the split reference (metrics::rel_mse_against_split_reference: the
//! references' own noise taken out) as mean, median and max over seeds, and bir's stats
//! averaged. Unclamped VPLs have an infinite-variance per-pixel estimator wherever a VPL can
//! land arbitrarily close to a visible surface, so the mean of relMSE over seeds is dominated
//! by its largest seed and the median is the stable figure of a typical render.

use std::path::{Path, PathBuf};

use irad::gpu::{Context, ContextOptions, Validation};
use irad::image::{exr, metrics, Image};
use irad::methods::bir::{Bir, BirSettings, Strategy};
use irad::methods::reference::{Reference, ReferenceSettings};
use irad::scene::gpu::GpuScene;

fn luminance_mean(image: &Image) -> f64 {
    metrics::luminance(image.mean().map(f64::from))
}

fn mean_and_stderr(values: &[f64]) -> (f64, f64) {
    let n = values.len() as f64;
    let mean = values.iter().sum::<f64>() / n;
    let var = values.iter().map(|m| (m - mean).powi(2)).sum::<f64>() / (n - 1.0).max(1.0);
    (mean, (var / n).sqrt())
}

fn settings(config: &str) -> Result<BirSettings, String> {
    let mut s = BirSettings::default();
    for kv in config.split(',').filter(|kv| !kv.is_empty()) {
        let (key, value) = kv
            .split_once('=')
            .ok_or_else(|| format!("`{kv}` in `{config}` is not key=value"))?;
        let bad = |e: &dyn std::fmt::Display| format!("{key}={value}: {e}");
        let int = || value.parse::<u32>().map_err(|e| bad(&e));
        match key {
            "strategy" => {
                s.strategy = match value {
                    "standard" => Strategy::Standard,
                    "reverse" => Strategy::Reverse,
                    "both" => Strategy::Both,
                    _ => return Err(bad(&"expected standard, reverse or both")),
                }
            }
            "vpls" => s.vpls = int()?,
            "frames" => s.frames = int()?,
            "ratio" => s.ratio = int()?,
            "pool" => s.pool = int()?,
            "power_samples" => s.power_samples = int()?,
            "light_samples" => s.light_samples = int()?,
            "depth" => s.depth = int()?,
            "connections" => s.connections = int()?,
            "batch" => s.batch = int()?,
            "floor" => s.floor = value.parse().map_err(|e| bad(&e))?,
            "adaptive" => s.adaptive = value == "1" || value == "true",
            _ => return Err(format!("unknown key `{key}` in `{config}`")),
        }
    }
    Ok(s)
}

fn reference(ctx: &Context, gpu: &GpuScene, path: &Path, spp: u32, seed: u32) -> Image {
    if let Ok(image) = exr::read(path) {
        return image;
    }
    eprintln!("rendering {} ({spp} spp)", path.display());
    let settings = ReferenceSettings {
        spp,
        seed,
        ..Default::default()
    };
    let out = Reference::new(ctx)
        .and_then(|r| r.render(ctx, gpu, &settings, |_, _| {}))
        .unwrap_or_else(|e| panic!("reference: {e}"));
    exr::write(path, &out.image).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    out.image
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    if args.len() < 5 {
        eprintln!("usage: bir_strategies SCENE.toml WIDTHxHEIGHT SEEDS REF_SPP CONFIG...");
        std::process::exit(2);
    }
    let scene_path = PathBuf::from(&args[0]);
    let (width, height) = args[1]
        .split_once('x')
        .and_then(|(w, h)| Some((w.parse::<u32>().ok()?, h.parse::<u32>().ok()?)))
        .unwrap_or_else(|| panic!("size `{}`: expected WIDTHxHEIGHT", args[1]));
    let seeds: u32 = args[2].parse().expect("SEEDS: a count");
    let ref_spp: u32 = args[3].parse().expect("REF_SPP: samples per pixel");
    let configs: Vec<(String, BirSettings)> = args[4..]
        .iter()
        .map(|c| (c.clone(), settings(c).unwrap_or_else(|e| panic!("{e}"))))
        .collect();

    let ctx = Context::new(&ContextOptions {
        device: None,
        validation: Validation::Off,
    })
    .expect("a Vulkan device");
    let mut scene = irad::scene::load(&scene_path).unwrap_or_else(|e| panic!("{e}"));
    scene.camera.width = width;
    scene.camera.height = height;
    let gpu = GpuScene::upload(&ctx, &scene).expect("scene upload");
    let cache = |seed: u32| {
        scene_path.with_file_name(format!(
            "bir_strategies_ref_{seed}_{width}x{height}_{ref_spp}.exr"
        ))
    };
    let a = reference(&ctx, &gpu, &cache(77), ref_spp, 77);
    let b = reference(&ctx, &gpu, &cache(78), ref_spp, 78);
    let own = metrics::compare(&a, &b).unwrap().rel_mse / 4.0;
    let mut r = a.clone();
    for (p, q) in r.pixels.iter_mut().zip(&b.pixels) {
        for c in 0..3 {
            p[c] = 0.5 * (p[c] + q[c]);
        }
    }
    let r_mean = luminance_mean(&r);
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
    let bir = Bir::new(&ctx).expect("bir kernels");
    for (name, base) in &configs {
        let (mut means, mut errors, mut gpu_ms) = (vec![], vec![], 0.0);
        let mut stats: Vec<(String, f64)> = vec![];
        for seed in 0..seeds {
            let s = BirSettings {
                seed: 1000 + seed,
                ..*base
            };
            let out = bir
                .render(&ctx, &scene, &gpu, &s, |_, _| {})
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
        let mut sorted = errors.clone();
        sorted.sort_by(f64::total_cmp);
        let stats: Vec<String> = stats.iter().map(|(k, v)| format!("{k} {v:.3}")).collect();
        println!(
            "{name}: mean {m:.3} ± {e:.3}; relMSE mean {:.4} median {:.4} max {:.4}; {gpu_ms:.0} GPU ms per render; {}",
            errors.iter().sum::<f64>() / errors.len() as f64,
            sorted[sorted.len() / 2],
            sorted[sorted.len() - 1],
            stats.join(", ")
        );
    }
}
