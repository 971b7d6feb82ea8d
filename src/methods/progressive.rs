//! Progressive rendering shared by every method: frames recorded in submissions of 1, 2, 4,
//! ... up to `MAX_FRAMES_PER_SUBMISSION` frames (so a progress bar stays live and the 512-pass
//! limit of one submission is never reached), the accumulation folded into f64 after each, GPU
//! time summed per pass name. The schedule depends only on the frame count, never on measured
//! time: submissions end the f32 sums, so a timing-driven schedule would change the bits of
//! the image from run to run (DESIGN.md: same seed, same device, same bits).

use crate::gpu::{Commands, Context, GpuResult, PassTotals};
use crate::scene::gpu::GpuScene;

use super::accumulation::Accumulation;

/// Most frames in one submission.
pub const MAX_FRAMES_PER_SUBMISSION: u32 = 16;

/// Records frames 0..frames with `record(cmd, frame)`, each submission starting with a clear
/// of `accumulation`'s GPU sums; calls `progress(done, frames)` after each submission. A frame
/// of a scene with a dynamic map starts with that frame's map (GpuScene's pass "environment
/// frame").
pub fn run<'s>(
    ctx: &Context,
    scene: &'s GpuScene,
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
            scene.record_environment_frame(&mut cmd, frame)?;
            record(&mut cmd, frame)?;
        }
        let timings = cmd.submit_and_wait()?;
        accumulation.collect()?;
        passes.add(&timings);
        done += count;
        progress(done, frames);
        batch = (2 * batch).min(MAX_FRAMES_PER_SUBMISSION);
    }
    Ok(passes)
}
