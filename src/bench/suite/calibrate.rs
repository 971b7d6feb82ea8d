//! Time budgets (`time_ms` in a suite budget): the count a method needs to fill that much GPU
//! time on this device. One unrecorded warm-up render at count 1, then short calibration
//! renders at growing counts (frames, or the reference's spp: `Method::count_key`), at least
//! two, until one takes at least a quarter of the budget; a line through the last two (GPU
//! time = fixed + count x per-count; the fixed part is what a render builds once: tables,
//! set-up) gives the count that fills it, rounded. The run then renders with that count like
//! any other budget, deterministic per seed, and records the count (a render with it gives the
//! same bits) and the calibration renders.
//!
//! Why the warm-up and the quarter: with no warm-up and an eighth, bir's 2 s and 8 s budgets
//! on the offices ran 0.8x-2.1x their budget (lavapipe, a machine shared with a reference
//! render; e.g. u-office 2 s: 1 frame 247 ms, 3 frames 448 ms, so 19 frames, which took
//! 3926 ms). A first render pays for first use (lazy driver work, cold caches), which makes
//! the line's fixed part too large and its slope too small; a longer last trial extrapolates
//! 4x instead of 8x. With both, 22 runs of bir and the path tracer on the offices (2 s and 8 s,
//! an otherwise idle machine) took 0.78-1.29x their budget.
//!
//! Calibration renders use seeds apart from the scored ones; their images are dropped.

use serde::{Deserialize, Serialize};

use crate::gpu::Context;
use crate::methods::{Method, Renderers};
use crate::scene::gpu::GpuScene;
use crate::scene::Scene;

use super::measure::MeasureError;

/// The largest count a time budget calibrates to.
pub const MAX_COUNT: u32 = 1 << 20;

/// Added to the method's seed for calibration renders: far from the scored seeds.
const CALIBRATION_SEED_OFFSET: u32 = 0x6361_6c69;

/// One calibration render.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Trial {
    pub count: u32,
    /// Its GPU time (its wall time where the device has no timestamps).
    pub ms: f64,
}

#[derive(Clone, Debug, PartialEq)]
pub struct Calibration {
    /// The count that fills the budget (at least 1, at most MAX_COUNT).
    pub count: u32,
    pub trials: Vec<Trial>,
}

/// The count of `method` that fills `time_ms` of GPU time; `progress(render, done, total)`
/// reports the calibration renders.
pub fn calibrate(
    ctx: &Context,
    renderers: &Renderers,
    method: &Method,
    scene: &Scene,
    gpu_scene: &GpuScene,
    time_ms: f64,
    mut progress: impl FnMut(u32, u32, u32),
) -> Result<Calibration, MeasureError> {
    let seed = method.seed().wrapping_add(CALIBRATION_SEED_OFFSET);
    let mut trials: Vec<Trial> = Vec::new();
    let mut count = 1u32;
    // The warm-up: first use is not part of the line (module comment).
    renderers.run(
        ctx,
        &method.with_count(1).with_seed(seed),
        scene,
        gpu_scene,
        |d, t| progress(0, d, t),
    )?;
    loop {
        let m = method.with_count(count).with_seed(seed);
        let render = trials.len() as u32 + 1;
        let out = renderers.run(ctx, &m, scene, gpu_scene, |d, t| progress(render, d, t))?;
        let ms = out.passes.total_gpu_ms().unwrap_or(out.wall_ms);
        trials.push(Trial { count, ms });
        if (trials.len() >= 2 && ms >= time_ms / 4.0) || count >= MAX_COUNT / 2 {
            break;
        }
        // Aim the next render at a third of the budget, growing 2x to 16x a step.
        let aim = (count as f64 * (time_ms / 3.0) / ms.max(1e-3)).ceil();
        count = (aim.clamp(2.0 * count as f64, 16.0 * count as f64) as u32).min(MAX_COUNT / 2);
    }
    Ok(Calibration {
        count: fill(&trials, time_ms),
        trials,
    })
}

/// A time budget cannot be met when the run, at the smallest count (1), took longer than it
/// (`ms`: its median GPU time, or wall time without timestamps). A run over its budget at a
/// larger count is the calibration's error, which a smaller count would have avoided.
pub fn missed(time_ms: f64, count: u32, ms: f64) -> bool {
    count <= 1 && ms > time_ms
}

/// The count whose predicted time is the budget, from the line through the last two trials
/// (one trial, or a line that does not rise: proportional to the last), at most 4x the
/// proportional count (a near-flat line through two noisy times would predict any count).
pub fn fill(trials: &[Trial], time_ms: f64) -> u32 {
    let Some(last) = trials.last() else {
        return 1;
    };
    let b = last.count as f64;
    // The fixed part (tables, set-up, built once per render).
    let fixed = match trials.len() {
        0 | 1 => 0.0,
        n => {
            let prev = trials[n - 2];
            let a = prev.count as f64;
            let per = (last.ms - prev.ms) / (b - a);
            let fixed = prev.ms - per * a;
            if b > a && per > 0.0 && fixed.is_finite() {
                fixed.clamp(0.0, prev.ms)
            } else {
                0.0
            }
        }
    };
    let per = (last.ms - fixed) / b;
    if per.is_nan() || per <= 0.0 {
        return MAX_COUNT;
    }
    let proportional = time_ms / last.ms * b;
    ((time_ms - fixed) / per)
        .min(4.0 * proportional)
        .round()
        .clamp(1.0, MAX_COUNT as f64) as u32
}

#[cfg(test)]
mod tests {
    use super::*;

    fn trials(t: &[(u32, f64)]) -> Vec<Trial> {
        t.iter().map(|&(count, ms)| Trial { count, ms }).collect()
    }

    #[test]
    fn a_line_through_two_trials_fills_the_budget() {
        // 10 ms fixed + 5 ms per count: 1000 ms holds 198 counts.
        assert_eq!(fill(&trials(&[(4, 30.0), (32, 170.0)]), 1000.0), 198);
        // A large fixed part (a 400 ms table build, 100 ms a frame) is kept whole.
        assert_eq!(fill(&trials(&[(1, 500.0), (2, 600.0)]), 2000.0), 16);
    }

    #[test]
    fn one_trial_is_proportional_and_a_count_is_at_least_one() {
        assert_eq!(fill(&trials(&[(1, 400.0)]), 2000.0), 5);
        assert_eq!(fill(&trials(&[(1, 5000.0)]), 2000.0), 1);
        // Two trials of one count: no line, proportional to the last.
        assert_eq!(fill(&trials(&[(2, 100.0), (2, 100.0)]), 1000.0), 20);
    }

    #[test]
    fn a_budget_is_missed_only_when_one_count_is_over_it() {
        assert!(missed(1.0, 1, 4.2));
        assert!(!missed(1.0, 1, 0.9));
        // Over the budget at 7 frames: 6 would have been under; not a budget that cannot be met.
        assert!(!missed(1.0, 7, 1.3));
    }

    #[test]
    fn a_noisy_line_never_predicts_wildly() {
        // The second trial faster than the first: no line, proportional (1000 / 45).
        assert_eq!(fill(&trials(&[(1, 100.0), (2, 90.0)]), 1000.0), 22);
        // Nearly flat: the line would predict 10 x the proportional count; capped at 4x.
        assert_eq!(fill(&trials(&[(1, 100.0), (2, 101.0)]), 1000.0), 79);
    }
}
