//! `irad bench lightfield`: the per-frame breakdown of the `lightfield` method (Lu 14 Fig. 4.12)
//! for each strategy and sample budget K. Every figure is a GPU time per frame: the median over
//! `repeats` timed renders of its mean over their frames, after one untimed warm-up render:
//! - G-buffer: passes "gbuffer" and "direct light" (the other lights, and the emission seen);
//! - tables: passes "luminaire tables" and "luminaire frame": the sampling tables' build, in
//!   the frame only for a luminaire whose atlases change (a still one builds them once per
//!   render: Lu's precomputation, reported beside the frame);
//! - A estimation: pass "A estimation" (Lu's step 1);
//! - sampling: pass "shade" of a sampling-only render: per image K_m (A_m computed again, as
//!   in Lu's step 2) and the samples drawn, nothing shaded;
//! - shading: "shade" without shadow rays, less sampling (C_m, Psi_m, the BRDF, accumulation);
//! - shadows: "shade" with a shadow ray per sample, less "shade" without.
//!
//! Lu's "acc. buffer" (16% of his frame) was the per-image passes' accumulation; here each
//! luminaire adds its sum once per pixel at the end of "shade", so it is part of shading.

use anyhow::Result;

use super::median;

use crate::methods::interface::{self, Renderer};
use crate::methods::lightfield::{Lightfield, LightfieldSettings, Strategy};
use crate::methods::RenderOutput;
use crate::scene::gpu::GpuScene;
use crate::scene::Scene;

/// One row: a strategy at K samples per pixel, luminaire and frame.
pub struct LightfieldTiming {
    pub strategy: Strategy,
    pub spp: u32,
    pub gbuffer_ms: f64,
    /// One build of every luminaire's tables.
    pub tables_build_ms: f64,
    /// The tables' share of a frame: 0 unless an atlas sequence rebuilds them every frame.
    pub tables_ms: f64,
    pub estimate_ms: f64,
    pub sampling_ms: f64,
    pub shading_ms: f64,
    pub shadows_ms: f64,
    /// Samples drawn per lit pixel and frame (over all luminaires).
    pub samples_per_pixel: f64,
}

impl LightfieldTiming {
    /// The frame with a shadow ray per sample.
    pub fn frame_ms(&self) -> f64 {
        self.gbuffer_ms
            + self.tables_ms
            + self.estimate_ms
            + self.sampling_ms
            + self.shading_ms
            + self.shadows_ms
    }
}

fn pass_per_frame(out: &RenderOutput, names: &[&str], frames: u32) -> f64 {
    // Summed over the render, per frame (or per build).
    out.passes
        .passes
        .iter()
        .filter(|p| names.contains(&p.0.as_str()))
        .filter_map(|p| p.1)
        .sum::<f64>()
        / frames as f64
}

/// For each strategy and K: three kinds of render of `frames` frames (with shadow rays,
/// without, and sampling only), `repeats` times each, after a one-frame warm-up.
#[allow(clippy::too_many_arguments)]
pub fn run(
    ctx: &crate::gpu::Context,
    scene: &Scene,
    strategies: &[Strategy],
    spps: &[u32],
    k_max: u32,
    frames: u32,
    repeats: usize,
    mut progress: impl FnMut(Strategy, u32),
) -> Result<Vec<LightfieldTiming>> {
    if let Some(e) = interface::declines::<Lightfield>(scene) {
        anyhow::bail!("bench lightfield: {e}");
    }
    let gpu = GpuScene::upload(ctx, scene)?;
    let lightfield = Renderer::<Lightfield>::new(ctx)?;
    let frames = frames.max(1);
    let sequence = scene
        .luminaires
        .iter()
        .any(|l| !l.luminaire.sequence.is_empty());
    // Builds of every luminaire's tables: one "luminaire tables" pass per luminaire each.
    let builds = |out: &RenderOutput| {
        out.passes
            .passes
            .iter()
            .find(|p| p.0 == "luminaire tables")
            .map_or(1, |p| (p.2 / scene.luminaires.len().max(1) as u32).max(1))
    };
    let mut results = vec![];
    for &strategy in strategies {
        for &spp in spps {
            progress(strategy, spp);
            let settings = |frames, shadows, sampling_only| LightfieldSettings {
                spp,
                frames,
                strategy,
                k_max,
                shadows,
                sampling_only,
                ..Default::default()
            };
            let kinds = [(true, false), (false, false), (false, true)];
            for &(shadows, sampling_only) in &kinds {
                lightfield.render(
                    ctx,
                    scene,
                    &gpu,
                    &settings(1, shadows, sampling_only),
                    |_, _| {},
                )?;
            }
            // Repeats interleave the three kinds, so a slow spell of the machine hits all.
            let mut runs: Vec<[RenderOutput; 3]> = Vec::with_capacity(repeats.max(1));
            for _ in 0..repeats.max(1) {
                let render = |(shadows, sampling_only)| {
                    lightfield.render(
                        ctx,
                        scene,
                        &gpu,
                        &settings(frames, shadows, sampling_only),
                        |_, _| {},
                    )
                };
                runs.push([render(kinds[0])?, render(kinds[1])?, render(kinds[2])?]);
            }
            let med = |f: &dyn Fn(&[RenderOutput; 3]) -> f64| {
                let mut v: Vec<f64> = runs.iter().map(f).collect();
                median(&mut v)
            };
            let shade = |out: &RenderOutput| pass_per_frame(out, &["shade"], frames);
            let sampling_ms = med(&|r| shade(&r[2]));
            let unshadowed_ms = med(&|r| shade(&r[1]));
            results.push(LightfieldTiming {
                strategy,
                spp,
                gbuffer_ms: med(&|r| pass_per_frame(&r[0], &["gbuffer", "direct light"], frames)),
                tables_build_ms: med(&|r| {
                    pass_per_frame(&r[0], &["luminaire tables"], builds(&r[0]))
                }),
                tables_ms: if sequence {
                    med(&|r| {
                        pass_per_frame(&r[0], &["luminaire tables", "luminaire frame"], frames)
                    })
                } else {
                    0.0
                },
                estimate_ms: med(&|r| pass_per_frame(&r[0], &["A estimation"], frames)),
                sampling_ms,
                shading_ms: unshadowed_ms - sampling_ms,
                shadows_ms: med(&|r| shade(&r[0])) - unshadowed_ms,
                samples_per_pixel: runs[0][0]
                    .stats
                    .iter()
                    .find(|s| s.0 == "luminaire_samples_per_pixel")
                    .map_or(f64::NAN, |s| s.1),
            });
        }
    }
    Ok(results)
}

pub fn print(device: &str, scene: &Scene, k_max: u32, frames: u32, results: &[LightfieldTiming]) {
    println!(
        "lightfield per frame on {device}: {} at {}x{}, {} luminaire(s), K_max {k_max} (mean GPU ms over {frames} frames; Lu 14 Fig. 4.12)",
        scene.name,
        scene.camera.width,
        scene.camera.height,
        scene.luminaires.len()
    );
    if let Some(r) = results.first() {
        println!(
            "tables (Lu's precomputation: CDFs and summed-area tables of every image): {:.2} ms per build{}",
            r.tables_build_ms,
            if r.tables_ms > 0.0 {
                ", rebuilt every frame (an atlas sequence)"
            } else {
                ", once per render"
            }
        );
    }
    println!(
        "{:>12} {:>5} {:>8} {:>9} {:>7} {:>10} {:>10} {:>10} {:>10} {:>10} {:>10}",
        "strategy",
        "K",
        "samples",
        "frame",
        "fps",
        "G-buffer",
        "tables",
        "A est.",
        "sampling",
        "shading",
        "shadows"
    );
    for r in results {
        let frame = r.frame_ms();
        let share = |ms: f64| format!("{ms:.1} {:>2.0}%", 100.0 * ms / frame);
        println!(
            "{:>12} {:>5} {:>8.1} {:>9.2} {:>7.2} {:>10} {:>10} {:>10} {:>10} {:>10} {:>10}",
            r.strategy.name(),
            r.spp,
            r.samples_per_pixel,
            frame,
            1e3 / frame,
            share(r.gbuffer_ms),
            share(r.tables_ms),
            share(r.estimate_ms),
            share(r.sampling_ms),
            share(r.shading_ms),
            share(r.shadows_ms)
        );
    }
    println!(
        "samples: drawn per lit pixel and frame; sampling: K_m and the draws (sampling-only render); shading: C_m, Psi_m, BRDF and accumulation, without visibility; shadows: one ray per sample (differences of medians: a small one can come out negative)"
    );
}
