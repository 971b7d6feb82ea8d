//! One frame-time run of a suite (`budgets = [{ frame_ms = X }]` on an animated scene),
//! measured: its count is calibrated on one frame (the caller, calibrate.rs), then `warmup`
//! untimed renders of that frame, then the scene's frames rendered as a sequence
//! (`crate::sequence::render_frames`: each frame its own scene and seed, independent of the
//! others) once per seed, `repeats` seeds: sequence r uses the method's seed + r x B (B the
//! end of the frames), so no two renders of the run share a seed. A method that carries state
//! across frames (restir's reservoirs) renders up to `lead_in` frames before the scored ones,
//! unscored and untimed, so its first scored frame has the history a running application's
//! would. Each frame is scored against
//! its own reference (`SequenceScore`: relMSE, bias, outliers per frame, and the flicker of
//! the sequence). Reported: per frame its figures averaged over the seeds and its GPU time's
//! median; for the run the median frame time, the figures' mean over every frame and seed,
//! the worst frame and the flicker (mean over the seeds).

use std::collections::BTreeMap;
use std::ops::Range;

use crate::bench::median;
use crate::gpu::Context;
use crate::image::{Image, Metrics, SequenceScore};
use crate::methods::{Method, Renderers, RunError};
use crate::scene::gpu::GpuScene;
use crate::scene::Scene;

use super::measure::MeasureError;
use super::results::{FrameResult, SequenceResult};

pub struct MeasuredSequence {
    /// The calibration frame of the first sequence, and its reference (the run's thumbnail
    /// and error map).
    pub image: Image,
    pub image_reference: Image,
    /// Each figure's mean over every frame and seed (NaN/Inf counts summed).
    pub metrics: Metrics,
    /// Frames scored (frames x seeds).
    pub scored: u32,
    /// The lowest and highest of the sequences' mean relMSE (one per seed).
    pub rel_mse_range: Option<(f64, f64)>,
    /// Median over every frame and seed of the frame's GPU time (None where the device has no
    /// timestamps), of each pass's, and of the frame's wall time.
    pub gpu_ms: Option<f64>,
    pub pass_gpu_ms: BTreeMap<String, Option<f64>>,
    pub wall_ms: f64,
    pub nonfinite_estimates: u64,
    pub stats: BTreeMap<String, f64>,
    /// The mean of the frame references' own relMSE.
    pub reference_rel_mse: Option<f64>,
    /// Each image's mean over its frame's reference's, less one, averaged over every frame
    /// and seed, and the standard deviation of those ratios: a method that estimates another
    /// quantity than the reference (direct light against a full reference: env 0.962 of it on
    /// moving-sun-sequence) shows here as an offset many spreads / sqrt(n) from zero.
    pub image_mean_offset: f64,
    pub image_mean_spread: Option<f64>,
    pub sequence: SequenceResult,
    /// Frames rendered, unscored, before each sequence's scored frames.
    pub lead_in: u32,
}

/// The frames a sequence of a run renders: `frames`, after up to `lead_in` frames before them
/// (as many as the animation has) for a method that carries state across frames.
fn rendered_frames(frames: &Range<u32>, lead_in: u32, carries_nothing: bool) -> Range<u32> {
    let lead_in = if carries_nothing {
        0
    } else {
        lead_in.min(frames.start)
    };
    frames.start - lead_in..frames.end
}

/// Renders `method` (its calibrated count) over `frames` of the animated `scene`, once per
/// seed; `references[i]` is frame `frames.start + i`'s (frame, reference, its relMSE);
/// `still` and `gpu` are the calibration frame's scene and upload, for the warm-up.
/// `progress(render, renders, done, total)` counts frames.
#[allow(clippy::too_many_arguments)]
pub fn measure_sequence(
    ctx: &Context,
    renderers: &Renderers,
    method: &Method,
    scene: &Scene,
    still: &Scene,
    gpu: &GpuScene,
    frames: Range<u32>,
    calibration_frame: u32,
    references: &[(u32, Image, Option<f64>)],
    warmup: u32,
    repeats: u32,
    lead_in: u32,
    progress: &mut impl FnMut(u32, u32, u32, u32),
) -> Result<MeasuredSequence, MeasureError> {
    let n = frames.len() as u32;
    if n == 0 || references.len() != frames.len() {
        return Err(MeasureError::Failed(format!(
            "{} frame references for frames {}..{}",
            references.len(),
            frames.start,
            frames.end
        )));
    }
    let repeats = repeats.max(1);
    let renders = warmup + repeats * n;
    let seed = method.seed();
    let stride = frames.end;
    for w in 0..warmup {
        // After every scored seed, as measure.rs's warm-ups.
        let m = method.with_seed(seed.wrapping_add(repeats * stride + w));
        renderers.run(ctx, &m, still, gpu, |d, t| progress(w, renders, d, t))?;
    }
    let mut image = None;
    let mut gpu_ms: Vec<Vec<Option<f64>>> = vec![Vec::new(); n as usize];
    let mut wall = Vec::new();
    let mut passes: BTreeMap<String, Vec<Option<f64>>> = BTreeMap::new();
    let mut nonfinite = 0u64;
    let mut relative: Vec<f64> = Vec::new();
    let mut stats: BTreeMap<String, f64> = BTreeMap::new();
    let mut sequences = Vec::new();
    for r in 0..repeats {
        let m = method.with_seed(seed.wrapping_add(r * stride));
        // HDR-FLIP per frame too (a few ms a frame at suite sizes in release).
        let mut score = SequenceScore::with_flip(crate::image::flip::DEFAULT_PIXELS_PER_DEGREE);
        // The suite's kernels, which the warm-ups above built and warmed.
        let rendered = crate::sequence::render_frames_with(
            ctx,
            renderers,
            scene,
            &m,
            rendered_frames(&frames, lead_in, method.across_frames().carries_nothing()),
            |f, _, out| {
                if f < frames.start {
                    return Ok(());
                }
                let i = (f - frames.start) as usize;
                let reference = &references[i].1;
                if r == 0 && f == calibration_frame {
                    image = Some(out.image.clone());
                }
                gpu_ms[i].push(out.passes.total_gpu_ms());
                wall.push(out.wall_ms);
                for (name, ms, _) in &out.passes.passes {
                    passes.entry(name.clone()).or_default().push(*ms);
                }
                nonfinite += out.nonfinite_estimates as u64;
                let channel_mean = |im: &Image| im.mean().iter().sum::<f64>() / 3.0;
                relative.push(channel_mean(&out.image) / channel_mean(reference));
                for (name, value) in &out.stats {
                    *stats.entry(name.clone()).or_default() += value / f64::from(repeats * n);
                }
                score
                    .push(out.image, reference.clone())
                    .map_err(|e| anyhow::anyhow!("scoring frame {f} against its reference: {e}"))?;
                progress(warmup + r * n + i as u32 + 1, renders, 1, 1);
                Ok(())
            },
        );
        if let Err(e) = rendered {
            return Err(match e.downcast::<RunError>() {
                Ok(run) => MeasureError::from(run),
                Err(e) => MeasureError::Failed(format!("{e:#}")),
            });
        }
        sequences.push(score.finish());
    }
    let median_of = |values: &[Option<f64>]| -> Option<f64> {
        let mut v: Vec<f64> = values.iter().copied().collect::<Option<Vec<f64>>>()?;
        Some(median(&mut v))
    };
    let per_frame: Vec<FrameResult> = frames
        .clone()
        .enumerate()
        .map(|(i, f)| {
            let over_seeds: Vec<Metrics> = sequences.iter().map(|(p, _)| p[i]).collect();
            FrameResult {
                frame: f,
                metrics: Metrics::mean(&over_seeds),
                gpu_ms: median_of(&gpu_ms[i]).unwrap_or(f64::NAN),
            }
        })
        .collect();
    let all: Vec<Metrics> = sequences.iter().flat_map(|(p, _)| p.clone()).collect();
    // A frame whose relMSE is NaN (NaN/Inf pixels) is the worst: the first such frame, else
    // the highest relMSE.
    let worst_key = |e: f64| if e.is_nan() { f64::INFINITY } else { e };
    let (worst_frame, worst_rel_mse) = per_frame
        .iter()
        .map(|p| (p.frame, p.metrics.rel_mse))
        .reduce(|(wf, w), (f, e)| match worst_key(e) > worst_key(w) {
            true => (f, e),
            false => (wf, w),
        })
        .unwrap_or((frames.start, f64::NAN));
    let flickers: Vec<f64> = sequences.iter().map(|(_, s)| s.flicker).collect();
    let flicker = flickers.iter().sum::<f64>() / flickers.len() as f64;
    let means: Vec<f64> = sequences
        .iter()
        .map(|(_, s)| s.mean.rel_mse)
        .filter(|e| e.is_finite())
        .collect();
    let all_gpu: Vec<Option<f64>> = gpu_ms.iter().flatten().copied().collect();
    let calibration_index = (calibration_frame - frames.start) as usize;
    Ok(MeasuredSequence {
        image: image.ok_or_else(|| {
            MeasureError::Failed(format!(
                "calibration frame {calibration_frame} is not among frames {}..{}",
                frames.start, frames.end
            ))
        })?,
        image_reference: references[calibration_index].1.clone(),
        metrics: Metrics::mean(&all),
        scored: repeats * n,
        rel_mse_range: means.iter().fold(None, |r: Option<(f64, f64)>, &e| {
            Some(r.map_or((e, e), |(lo, hi)| (lo.min(e), hi.max(e))))
        }),
        gpu_ms: median_of(&all_gpu),
        pass_gpu_ms: passes
            .iter()
            .map(|(k, v)| (k.clone(), median_of(v)))
            .collect(),
        wall_ms: median(&mut wall),
        nonfinite_estimates: nonfinite,
        stats,
        // The mean of the frames' own relMSEs, as the run's relMSE is the mean over frames
        // (net relMSE subtracts it); None unless every frame's reference has one.
        reference_rel_mse: references
            .iter()
            .map(|(_, _, e)| *e)
            .collect::<Option<Vec<f64>>>()
            .filter(|v| !v.is_empty())
            .map(|v| v.iter().sum::<f64>() / v.len() as f64),
        image_mean_offset: relative.iter().sum::<f64>() / relative.len().max(1) as f64 - 1.0,
        image_mean_spread: super::measure::spread(&relative),
        sequence: SequenceResult {
            frames: [frames.start, frames.end],
            calibration_frame,
            per_frame,
            worst_frame,
            worst_rel_mse: Some(worst_rel_mse).filter(|e| e.is_finite()),
            flicker: Some(flicker).filter(|e| e.is_finite()),
        },
        lead_in: frames.start
            - rendered_frames(&frames, lead_in, method.across_frames().carries_nothing()).start,
    })
}

#[cfg(test)]
mod tests {
    use super::rendered_frames;

    #[test]
    fn a_stateful_method_leads_in_as_far_as_the_animation_goes() {
        assert_eq!(rendered_frames(&(22..27), 6, false), 16..27);
        assert_eq!(rendered_frames(&(3..5), 6, false), 0..5);
        assert_eq!(rendered_frames(&(22..27), 6, true), 22..27);
        assert_eq!(rendered_frames(&(22..27), 0, false), 22..27);
    }
}
