//! Time left in a suite, for its progress bar: each remaining run is estimated from the wall
//! time per unit of work (renders x `Method::work` x pixels) of the finished runs of the same method
//! label, or of all finished runs when its label has not run yet. Runs of one label scale
//! about linearly in their samples; labels differ by orders of magnitude, so they are not
//! pooled when they need not be. A time-budget run is estimated from its budget.

use std::collections::BTreeMap;
use std::time::Duration;

use super::file::{RunSpec, Suite};

#[derive(Default)]
pub struct Eta {
    /// Per label: (seconds, units) of its finished runs.
    by_label: BTreeMap<String, (f64, f64)>,
    all: (f64, f64),
}

/// A run's work: renders x `Method::work` x pixels.
pub fn units(suite: &Suite, run: &RunSpec) -> f64 {
    let cam = &suite.scenes[run.scene].scene.camera;
    (suite.warmup + suite.repeats.max(suite.flicker_frames)) as f64
        * run.method.work()
        * cam.width as f64
        * cam.height as f64
}

impl Eta {
    /// `run` took `seconds` (its scene's reference included, when it came first).
    pub fn finished(&mut self, suite: &Suite, run: &RunSpec, seconds: f64) {
        if run.time_ms.is_some() || run.frame_ms.is_some() {
            // Its time is its budget (time_left), not a rate over its default count.
            return;
        }
        let u = units(suite, run);
        let label = &suite.entries[run.entry].label;
        let e = self.by_label.entry(label.clone()).or_default();
        e.0 += seconds;
        e.1 += u;
        self.all.0 += seconds;
        self.all.1 += u;
    }

    /// The estimated time of `remaining`, None before any run finished.
    pub fn left(&self, suite: &Suite, remaining: &[&RunSpec]) -> Option<Duration> {
        if self.all.1 <= 0.0 {
            return None;
        }
        let rate = |(s, u): (f64, f64)| s / u.max(1.0);
        let seconds: f64 = remaining
            .iter()
            .map(|r| {
                if let Some(t) = time_left(suite, r) {
                    return t;
                }
                let label = &suite.entries[r.entry].label;
                let per_unit = self
                    .by_label
                    .get(label)
                    .map_or(rate(self.all), |&e| rate(e));
                per_unit * units(suite, r)
            })
            .sum();
        Some(Duration::from_secs_f64(seconds.max(0.0)))
    }
}

/// A time-budget run's seconds: its renders at the budget each, plus about three quarters of a
/// budget of calibration, a typical figure (calibrate.rs: a warm-up, then trials until one
/// takes a quarter of it, each aimed at a third).
fn time_left(suite: &Suite, run: &RunSpec) -> Option<f64> {
    let renders = (suite.warmup + suite.repeats.max(suite.flicker_frames)) as f64;
    if let Some(ms) = run.frame_ms {
        // A frame-time run: the warm-ups and every frame of each repeat at the frame budget
        // (src/bench/suite/sequence.rs), and the calibration.
        // Plus the lead-in frames a method that carries state renders before each sequence's.
        let frames = suite.scenes[run.scene].frames.as_ref().map_or(1, |f| {
            let lead_in = match run.method.across_frames().carries_nothing() {
                true => 0,
                false => suite.lead_in.min(f.start),
            };
            f.len() + lead_in as usize
        }) as f64;
        let renders = suite.warmup as f64 + suite.repeats.max(1) as f64 * frames;
        return Some((renders + 0.75) * ms / 1e3);
    }
    run.time_ms.map(|ms| (renders + 0.75) * ms / 1e3)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn remaining_runs_are_estimated_per_label() {
        let text = "name = \"e\"\nwidth = 10\nwarmup = 0\nrepeats = 1\nflicker_frames = 0\n[reference]\nspp = 1\n[[scene]]\npath = \"embedded:cornell-box\"\n[[method]]\nmethod = \"reference\"\nbudgets = [{ spp = 1 }, { spp = 4 }]\n[[method]]\nmethod = \"ir\"\nbudgets = [{ frames = 1, vpls = 1 }, { frames = 2, vpls = 1 }]\n";
        let suite = Suite::parse("e.toml", text, std::path::Path::new(".")).unwrap();
        let runs: Vec<&RunSpec> = suite.runs.iter().collect();
        let mut eta = Eta::default();
        assert_eq!(eta.left(&suite, &runs), None);
        eta.finished(&suite, runs[0], 1.0);
        // spp 4 takes 4x spp 1; ir has not run, so it gets the overall rate (1 s per 100 units).
        let left = eta.left(&suite, &runs[1..]).unwrap().as_secs_f64();
        assert!((left - (4.0 + 1.0 + 2.0)).abs() < 1e-9, "{left}");
        eta.finished(&suite, runs[2], 10.0);
        let left = eta.left(&suite, &runs[3..]).unwrap().as_secs_f64();
        assert!((left - 20.0).abs() < 1e-9, "{left}");
    }
}
