//! Progressive rendering shared by every method: frames recorded in submissions of 1, 2, 4,
//! ... up to `MAX_FRAMES_PER_SUBMISSION` frames (so a progress bar stays live and the 512-pass
//! limit of one submission is never reached), the accumulation folded into f64 after each, GPU
//! time summed per pass name. The schedule depends only on the frame count, never on measured
//! time: submissions end the f32 sums, so a timing-driven schedule would change the bits of
//! the image from run to run (docs/DESIGN.md "Determinism": same seed, same device, same bits).

use std::cell::RefCell;

use crate::gpu::{Commands, Context, GpuResult, PassTotals};
use crate::scene::gpu::GpuScene;

use super::accumulation::Accumulation;

/// Most frames in one submission.
pub const MAX_FRAMES_PER_SUBMISSION: u32 = 16;

/// Told how far a submission under way has come (`observe_frames`).
pub type Observer = Box<dyn FnMut(Within)>;

thread_local! {
    static OBSERVER: RefCell<Option<Observer>> = const { RefCell::new(None) };
}

/// How far a submission under way has come.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Within {
    /// Frames done before the submission, and in it.
    pub frames_done: u32,
    pub frames: u32,
    /// Its dispatches done, and about how many it has: the first frame's count (recorded
    /// once without running), then the last submission's, per frame.
    pub dispatches_done: u32,
    pub dispatches: u32,
}

/// Installs `observer` (None removes it) for the renders on this thread: it is called as
/// parts of a submission complete. `progress` callbacks still count whole frames.
pub fn observe_frames(observer: Option<Observer>) {
    OBSERVER.with(|o| *o.borrow_mut() = observer);
}

fn observed() -> bool {
    OBSERVER.with(|o| o.borrow().is_some())
}

fn observe(within: Within) {
    OBSERVER.with(|o| {
        if let Some(observer) = o.borrow_mut().as_mut() {
            observer(within)
        }
    });
}

/// Records frames 0..frames with `record(cmd, frame)`, each submission starting with a clear
/// of `accumulation`'s GPU sums; calls `progress(done, frames)` after each submission. A frame
/// of a scene with a dynamic map starts with that frame's map (GpuScene's pass "environment
/// frame"). Fails with `GpuError::TraversalCut` after the first submission by whose end the
/// device's loop limit has cut a traversal of the scene's BVH short, in it or in a pass before
/// the frames (since the record was last cleared: `Renderers::run` clears it before a render).
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
    // Dispatches per frame, for the observer's fractions: the first frame's, recorded into
    // commands that are never submitted.
    let mut per_frame = 0u32;
    if observed() && frames > 0 {
        let mut probe = Commands::new(ctx)?;
        scene.record_environment_frame(&mut probe, 0)?;
        record(&mut probe, 0)?;
        per_frame = probe.dispatches();
    }
    while done < frames {
        let count = batch.min(frames - done);
        let mut cmd = Commands::new(ctx)?;
        if observed() {
            let expected = per_frame.max(1).saturating_mul(count);
            let first = done;
            // With an observer, the submission runs in parts, each waited for, so progress
            // shows within a long frame (bir's frame of 2^20 VPLs runs for minutes on
            // lavapipe). Parts change no bits: the accumulation is folded only after the whole
            // submission, and a part boundary only waits (Commands::on_progress).
            cmd.on_progress(Box::new(move |dispatches| {
                observe(Within {
                    frames_done: first,
                    frames: count,
                    dispatches_done: dispatches,
                    dispatches: expected.max(dispatches),
                })
            }));
        }
        accumulation.begin_submission(&mut cmd);
        for frame in done..done + count {
            scene.record_environment_frame(&mut cmd, frame)?;
            record(&mut cmd, frame)?;
        }
        per_frame = cmd.dispatches() / count;
        let timings = cmd.submit_and_wait()?;
        // Each submission's traversals (and those of the passes before the frames) whole, or
        // the render refused: a cut one leaves the image silently wrong.
        scene.bvh.check_loop_cuts()?;
        accumulation.collect()?;
        passes.add(&timings);
        done += count;
        progress(done, frames);
        batch = (2 * batch).min(MAX_FRAMES_PER_SUBMISSION);
    }
    Ok(passes)
}
