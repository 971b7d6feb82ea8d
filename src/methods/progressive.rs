//! Progressive rendering shared by every method: frames recorded in submissions that grow to
//! about a quarter second each (so a progress bar stays live and the 512-pass limit of one
//! submission is never reached), the accumulation folded into f64 after each, GPU time summed
//! per pass name.

use crate::gpu::{Commands, Context, GpuResult, PassTotals};

use super::accumulation::Accumulation;

/// Most frames in one submission.
const MAX_FRAMES_PER_SUBMISSION: u32 = 64;

/// Records frames 0..frames with `record(cmd, frame)`, each submission starting with a clear
/// of `accumulation`'s GPU sums; calls `progress(done, frames)` after each submission.
pub fn run<'s>(
    ctx: &Context,
    frames: u32,
    accumulation: &'s Accumulation,
    mut record: impl FnMut(&mut Commands<'s>, u32) -> GpuResult<()>,
    mut progress: impl FnMut(u32, u32),
) -> GpuResult<PassTotals> {
    let mut passes = PassTotals::default();
    let mut done = 0u32;
    let mut batch = 1u32;
    while done < frames {
        let count = batch.min(frames - done);
        let mut cmd = Commands::new(ctx)?;
        accumulation.begin_submission(&mut cmd);
        for frame in done..done + count {
            record(&mut cmd, frame)?;
        }
        let timings = cmd.submit_and_wait()?;
        accumulation.collect()?;
        passes.add(&timings);
        done += count;
        progress(done, frames);
        let per_frame_ms = timings.wall_ms / count as f64;
        batch = ((250.0 / per_frame_ms.max(1e-3)) as u32).clamp(1, MAX_FRAMES_PER_SUBMISSION);
    }
    Ok(passes)
}
