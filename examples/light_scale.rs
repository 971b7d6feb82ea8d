//! How each many-light sampler's cost and error grow with the light count (docs/many-lights-scale.md):
//! for each hall of `scripts/generate-many-lights.py --lights N`, its load and CPU builds (the
//! triangle BVH, the light BVH), the light data's device memory, then per frame at one sample
//! a pixel of direct light: the path tracer's GPU time with the power table and with the light
//! BVH, restir's (8 candidates through the light BVH, its candidates pass apart), and each
//! one's relMSE against a converged reference (the BVH path tracer at REF_SPP, two halves),
//! with relMSE x frame time, so that "at equal frame time" is the ratio of those products.
//!
//!   cargo run --release --example light_scale -- WIDTHxHEIGHT REF_SPP SEEDS HALL.toml ...

use std::time::Instant;

use irad::gpu::{Context, ContextOptions, GpuBuffer, Validation};
use irad::image::metrics;
use irad::methods::{Method, Renderers};
use irad::scene::gpu::GpuScene;

fn method(name: &str, params: &str) -> Method {
    let table: toml::Table = params.parse().unwrap_or_else(|e| panic!("{params}: {e}"));
    Method::from_params(name, &table).unwrap_or_else(|e| panic!("{name}: {e}"))
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    assert!(
        args.len() >= 4,
        "usage: WIDTHxHEIGHT REF_SPP SEEDS HALL.toml ..."
    );
    let (w, h) = args[0].split_once('x').expect("WIDTHxHEIGHT");
    let (width, height): (u32, u32) = (w.parse().unwrap(), h.parse().unwrap());
    let ref_spp: u32 = args[1].parse().unwrap();
    let seeds: u32 = args[2].parse().unwrap();
    let ctx = Context::new(&ContextOptions {
        device: None,
        validation: Validation::Off,
        force_staging: false,
    })
    .expect("a Vulkan device");
    let renderers = Renderers::default();
    println!(
        "| lights | load s | triangle BVH ms | light BVH ms | light data MiB | PT power ms | PT BVH ms \
         | restir ms (candidates) | PT power relMSE | PT BVH relMSE | restir relMSE \
         | BVH over power at equal time | restir over BVH at equal time |"
    );
    println!("|---:|---:|---:|---:|---:|---:|---:|---|---:|---:|---:|---:|---:|");
    for path in &args[3..] {
        let start = Instant::now();
        let mut scene =
            irad::scene::load(std::path::Path::new(path)).unwrap_or_else(|e| panic!("{e}"));
        let load_s = start.elapsed().as_secs_f64();
        scene.camera.width = width;
        scene.camera.height = height;
        let gpu = GpuScene::upload(&ctx, &scene).unwrap_or_else(|e| panic!("{path}: {e}"));
        let lights = gpu.light_table.entries.len();
        let light_bytes = gpu.light_entries.byte_size()
            + gpu.emitter_triangles.byte_size()
            + gpu.light_nodes.byte_size()
            + gpu.light_trails.byte_size();
        let render = |m: &Method| renderers.run(&ctx, m, &scene, &gpu, |_, _| {}).unwrap();
        let reference = |seed: u32| {
            let params =
                format!("spp = {ref_spp}\nmax_depth = 1\nlight_sampler = \"bvh\"\nseed = {seed}");
            render(&method("reference", &params)).image
        };
        let (a, b) = (reference(77), reference(78));
        // Median GPU ms of a frame and mean relMSE over seeds.
        let measure = |name: &str, params: &str, pass: Option<&str>| {
            let (mut ms, mut pass_ms, mut err) = (vec![], vec![], 0.0);
            for s in 0..seeds {
                let out = render(&method(name, &format!("{params}\nseed = {}", 100 + s)));
                ms.push(out.passes.total_gpu_ms().unwrap_or(out.wall_ms));
                if let Some(p) = pass {
                    let t = out.passes.passes.iter().find(|(n, _, _)| n == p);
                    pass_ms.push(t.and_then(|t| t.1).unwrap_or(0.0));
                }
                err += metrics::rel_mse_against_split_reference(&out.image, &a, &b).unwrap();
            }
            let median = |v: &mut Vec<f64>| {
                v.sort_by(f64::total_cmp);
                if v.is_empty() {
                    0.0
                } else {
                    v[v.len() / 2]
                }
            };
            (median(&mut ms), median(&mut pass_ms), err / seeds as f64)
        };
        let (power_ms, _, power_e) = measure(
            "reference",
            "spp = 1\nmax_depth = 1\nlight_sampler = \"power\"",
            None,
        );
        let (bvh_ms, _, bvh_e) = measure(
            "reference",
            "spp = 1\nmax_depth = 1\nlight_sampler = \"bvh\"",
            None,
        );
        let (restir_ms, cand_ms, restir_e) = measure(
            "restir",
            "frames = 1\ncandidates = 8\nneighbours = 2",
            Some("restir candidates"),
        );
        println!(
            "| {lights} | {load_s:.2} | {:.1} | {:.1} | {:.2} | {power_ms:.2} | {bvh_ms:.2} | {restir_ms:.2} ({cand_ms:.2}) \
             | {power_e:.4} | {bvh_e:.4} | {restir_e:.4} | {:.2}x | {:.2}x |",
            gpu.build_ms.triangle_bvh,
            gpu.build_ms.light_bvh,
            light_bytes as f64 / (1u64 << 20) as f64,
            (power_e * power_ms) / (bvh_e * bvh_ms),
            (bvh_e * bvh_ms) / (restir_e * restir_ms),
        );
    }
}
