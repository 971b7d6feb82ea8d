//! `irad bench ir`: per-pass GPU time of instant radiosity (walk, direct light, accumulation,
//! filter) for a range of VPL budgets, the accumulation throughput in (pixel, VPL slot) pairs
//! per second, and in the same run the incoherent any-hit ray rate of the same scene's BVH
//! (the target: pairs/s at least that ray rate, as each pair costs one shadow ray).

use anyhow::Result;

use crate::bvh::procedural;
use crate::gpu::Context;
use crate::methods::ir::{InstantRadiosity, IrSettings};
use crate::methods::Renderer;
use crate::scene::gpu::GpuScene;
use crate::scene::Scene;
use crate::trace::TraceMode;

use super::rays;

pub struct IrRow {
    pub paths: u32,
    /// Slots shaded per pixel (surface VPLs, empty slots of escaped paths included).
    pub slots: u32,
    /// Mean GPU ms per frame of each pass, in first-run order.
    pub passes: Vec<(String, f64)>,
    pub accumulation_ms: f64,
    pub pixels: u64,
    /// k: each pixel shades 1 / k^2 of the slots.
    pub interleave: u32,
}

impl IrRow {
    pub fn pairs_per_s(&self) -> f64 {
        let shaded = self.slots as f64 / (self.interleave * self.interleave) as f64;
        self.pixels as f64 * shaded / (self.accumulation_ms * 1e-3)
    }
}

pub struct IrReport {
    pub rows: Vec<IrRow>,
    /// Random (incoherent) any-hit rays/s through the same scene's BVH on the GPU.
    pub any_hit_rays_per_s: f64,
    pub frames: u32,
}

/// Renders `frames` frames per budget after a warm-up render, and traces `rays` random rays.
pub fn run(
    ctx: &Context,
    scene: &Scene,
    budgets: &[u32],
    frames: u32,
    interleave: u32,
    rays: usize,
    mut progress: impl FnMut(&str),
) -> Result<IrReport> {
    let gpu_scene = GpuScene::upload(ctx, scene)?;
    let ir = Renderer::<InstantRadiosity>::new(ctx)?;
    let settings = |paths, frames| IrSettings {
        paths,
        frames,
        interleave,
        ..Default::default()
    };
    progress("warm-up");
    ir.render(ctx, scene, &gpu_scene, &settings(64, 1), |_, _| {})?;
    let mut rows = Vec::new();
    for &paths in budgets {
        progress(&format!("{paths} paths"));
        let s = settings(paths, frames);
        let out = ir.render(ctx, scene, &gpu_scene, &s, |_, _| {})?;
        let per_frame = |ms: Option<f64>, count: u32| ms.unwrap_or(f64::NAN) / count as f64;
        let passes: Vec<(String, f64)> = out
            .passes
            .passes
            .iter()
            .map(|(name, ms, count)| (name.clone(), per_frame(*ms, *count)))
            .collect();
        let accumulation_ms = passes
            .iter()
            .find(|p| p.0 == "vpl accumulation")
            .map_or(f64::NAN, |p| p.1);
        let slots = InstantRadiosity::schedule(scene, &s).surface_slots().len() as u32;
        rows.push(IrRow {
            paths,
            slots,
            passes,
            accumulation_ms,
            pixels: gpu_scene.pixel_count() as u64,
            interleave: interleave.max(1),
        });
    }
    progress("rays");
    let triangles: Vec<_> = scene.triangles.iter().map(|t| t.positions).collect();
    let bounds = procedural::bounds(&triangles);
    let camera_rays = procedural::camera_rays(&crate::scene::Camera {
        width: 64,
        height: 64,
        ..scene.camera.clone()
    });
    let random_rays = procedural::random_rays(2, bounds, rays);
    let report = rays::run(ctx, &triangles, &camera_rays, &random_rays, 3)?;
    let any_hit_rays_per_s = report
        .rows
        .iter()
        .find(|r| r.set == "random" && r.mode == TraceMode::Any)
        .map_or(f64::NAN, |r| r.gpu_rays_per_s());
    Ok(IrReport {
        rows,
        any_hit_rays_per_s,
        frames,
    })
}

pub fn print_table(device: &str, scene: &str, width: u32, height: u32, report: &IrReport) {
    println!("instant radiosity on {device}: {scene} at {width}x{height}, mean GPU ms per frame over {} frames", report.frames);
    let names: Vec<&str> = report.rows.first().map_or(Vec::new(), |r| {
        r.passes.iter().map(|p| p.0.as_str()).collect()
    });
    print!("{:>7} {:>7}", "paths", "VPLs");
    for n in &names {
        print!(" {n:>17}");
    }
    println!(" {:>14} {:>12}", "Mpairs/s", "pairs/ray");
    let rays = report.any_hit_rays_per_s;
    for r in &report.rows {
        print!("{:>7} {:>7}", r.paths, r.slots);
        for (_, ms) in &r.passes {
            print!(" {ms:>14.2} ms");
        }
        println!(
            " {:>14.2} {:>12.2}",
            r.pairs_per_s() / 1e6,
            r.pairs_per_s() / rays
        );
    }
    println!(
        "random any-hit rays through the same BVH: {:.2} Mrays/s; target: pairs/s >= rays/s (pairs/ray >= 1)",
        rays / 1e6
    );
}
