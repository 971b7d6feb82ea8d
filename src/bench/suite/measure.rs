//! One run of a suite, measured: `warmup` untimed renders, then K = max(repeats, flicker
//! frames) renders with successive seeds (seed, seed + 1, ...). Reported: the median over the
//! first `repeats` of each pass's GPU time, of the total GPU time and of the wall time; the
//! error figures of every one of the K images against the reference, averaged (one image's
//! figures are as noisy as the image); and the flicker across the first F images (a static
//! view rendered frame after frame with fresh random numbers, as an animation shows it).

use std::collections::BTreeMap;

use crate::bench::median;
use crate::gpu::Context;
use crate::image::{self, metrics, Image, Metrics};
use crate::methods::{Method, Renderers, RunError};
use crate::scene::gpu::GpuScene;
use crate::scene::Scene;

/// Why a run has no figures.
#[derive(Debug)]
pub enum MeasureError {
    /// The method does not handle something in the scene.
    Declined(String),
    Failed(String),
}

impl From<RunError> for MeasureError {
    fn from(e: RunError) -> Self {
        match e {
            RunError::Declined(why) => MeasureError::Declined(why),
            RunError::Gpu(g) => MeasureError::Failed(g.to_string()),
            RunError::Animated(why) => MeasureError::Failed(why),
        }
    }
}

/// The sample standard deviation of `values`, or None below two values or where one is not
/// finite.
pub fn spread(values: &[f64]) -> Option<f64> {
    let n = values.len();
    if n < 2 || values.iter().any(|v| !v.is_finite()) {
        return None;
    }
    let mean = values.iter().sum::<f64>() / n as f64;
    let ss: f64 = values.iter().map(|v| (v - mean) * (v - mean)).sum();
    Some((ss / (n - 1) as f64).sqrt())
}

pub struct Measured {
    /// The first timed repeat's image (seed = the method's seed).
    pub image: Image,
    /// Each figure averaged over the K images (NaN/Inf counts summed).
    pub metrics: Metrics,
    /// Images scored.
    pub scored: u32,
    pub flicker: Option<f64>,
    /// The mean over the K images of the image mean (pixels and channels together), relative
    /// to the reference's, minus 1: signed, so noise averages out over the images (the bias
    /// figure averages each image's absolute offset). NaN where an image has NaN/Inf.
    pub image_mean_offset: f64,
    /// The standard deviation over the K images of the image mean relative to the reference's
    /// (the spread a user sees from one render to the next), or None below two images or
    /// where an image has NaN/Inf.
    pub image_mean_spread: Option<f64>,
    /// The lowest and highest relMSE of the K images (`metrics` has their mean).
    pub rel_mse_range: Option<(f64, f64)>,
    pub gpu_ms: Option<f64>,
    pub pass_gpu_ms: BTreeMap<String, Option<f64>>,
    pub wall_ms: f64,
    pub nonfinite_estimates: u64,
    /// The method's own figures, averaged over the scored images.
    pub stats: BTreeMap<String, f64>,
}

/// Renders `method` `warmup + max(repeats, flicker_frames)` times; `progress(render, renders,
/// done, total)` reports the render under way and its samples.
#[allow(clippy::too_many_arguments)]
pub fn measure(
    ctx: &Context,
    renderers: &Renderers,
    method: &Method,
    scene: &Scene,
    gpu_scene: &GpuScene,
    reference: &Image,
    warmup: u32,
    repeats: u32,
    flicker_frames: u32,
    mut progress: impl FnMut(u32, u32, u32, u32),
) -> Result<Measured, MeasureError> {
    let repeats = repeats.max(1);
    let k = repeats.max(flicker_frames);
    let renders = warmup + k;
    let seed = method.seed();
    for w in 0..warmup {
        // Warm-up seeds follow the scored ones, so no scored image repeats one.
        let m = method.with_seed(seed.wrapping_add(k + w));
        renderers.run(ctx, &m, scene, gpu_scene, |d, t| progress(w, renders, d, t))?;
    }
    let mut images = Vec::with_capacity(repeats as usize);
    let mut gpu = Vec::new();
    let mut wall = Vec::new();
    let mut passes: BTreeMap<String, Vec<Option<f64>>> = BTreeMap::new();
    let mut nonfinite = 0u64;
    let mut stats: BTreeMap<String, f64> = BTreeMap::new();
    for r in 0..k {
        let m = method.with_seed(seed.wrapping_add(r));
        let out = renderers.run(ctx, &m, scene, gpu_scene, |d, t| {
            progress(warmup + r, renders, d, t)
        })?;
        if r < repeats {
            gpu.push(out.passes.total_gpu_ms());
            wall.push(out.wall_ms);
            for (name, ms, _) in &out.passes.passes {
                passes.entry(name.clone()).or_default().push(*ms);
            }
        }
        nonfinite += out.nonfinite_estimates as u64;
        for (name, value) in &out.stats {
            *stats.entry(name.clone()).or_default() += value / k as f64;
        }
        images.push(out.image);
    }
    let median_of = |values: &[Option<f64>]| -> Option<f64> {
        let mut v: Vec<f64> = values.iter().copied().collect::<Option<Vec<f64>>>()?;
        Some(median(&mut v))
    };
    let scores = images
        .iter()
        .map(|im| image::compare(im, reference))
        .collect::<Result<Vec<Metrics>, _>>()
        .map_err(|e| MeasureError::Failed(format!("scoring against the reference: {e}")))?;
    let flicker = if flicker_frames >= 2 {
        Some(
            metrics::flicker(&images[..flicker_frames as usize], reference)
                .map_err(|e| MeasureError::Failed(format!("measuring flicker: {e}")))?,
        )
    } else {
        None
    };
    let channel_mean = |im: &Image| im.mean().iter().sum::<f64>() / 3.0;
    let relative: Vec<f64> = images
        .iter()
        .map(|im| channel_mean(im) / channel_mean(reference))
        .collect();
    let image_mean_offset = relative.iter().sum::<f64>() / relative.len() as f64 - 1.0;
    Ok(Measured {
        metrics: Metrics::mean(&scores),
        image_mean_offset,
        image_mean_spread: spread(&relative),
        rel_mse_range: scores
            .iter()
            .map(|m| m.rel_mse)
            .filter(|e| e.is_finite())
            .fold(None, |r: Option<(f64, f64)>, e| {
                Some(r.map_or((e, e), |(lo, hi)| (lo.min(e), hi.max(e))))
            }),
        scored: k,
        flicker,
        gpu_ms: median_of(&gpu),
        pass_gpu_ms: passes
            .iter()
            .map(|(k, v)| (k.clone(), median_of(v)))
            .collect(),
        wall_ms: median(&mut wall),
        nonfinite_estimates: nonfinite,
        stats,
        image: images.swap_remove(0),
    })
}

#[cfg(test)]
mod tests {
    use super::spread;

    #[test]
    fn spread_is_the_sample_standard_deviation() {
        // Means 0.8, 1.0, 1.2: deviations -0.2, 0, 0.2; sum of squares 0.08 over 2.
        let s = spread(&[0.8, 1.0, 1.2]).unwrap();
        assert!((s - 0.2).abs() < 1e-12, "{s}");
        assert_eq!(spread(&[1.0]), None);
        assert_eq!(spread(&[1.0, f64::NAN]), None);
    }
}
