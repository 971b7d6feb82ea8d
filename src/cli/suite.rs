//! `irad bench suite`: runs a suite with its progress bars, Ctrl-C handling and run lines.

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Instant;

use anyhow::{bail, Context as _, Result};
use indicatif::{MultiProgress, ProgressBar, ProgressStyle};

use irad::bench::suite::eta::Eta;
use irad::bench::suite::file::RunSpec;
use irad::bench::suite::{
    self, Event, RunRecord, Shard, Status, Suite, SuiteOptions, SuiteResults,
};
use irad::gpu::{Context, ContextOptions};
use irad::methods::reference::Reference;

use super::device_line;

#[derive(clap::Args)]
pub struct SuiteArgs {
    /// Suite TOML file (format in docs/suites.md); scenes/failure/suite.toml
    /// is the stability suite.
    #[arg(required_unless_present = "quick", conflicts_with = "quick")]
    suite: Option<PathBuf>,
    /// Run the built-in quick suite (scenes/suites/quick.toml of the source tree: 64 pixels wide,
    /// a few budgets; about a minute on lavapipe).
    #[arg(long)]
    quick: bool,
    /// Output folder [default: out/bench/<suite name>, with -shard-I-of-N for a shard].
    #[arg(short, long, value_name = "DIR")]
    out: Option<PathBuf>,
    /// Reference cache folder, shared by suites and shards.
    #[arg(long, value_name = "DIR", default_value = "out/references")]
    cache: PathBuf,
    /// Run only part I of N (0-based) of the suite: run k belongs to part k mod N. Merge
    /// the parts with `irad bench merge`.
    // Hyphen values reach Shard's parser, whose error names the value and the form it takes
    // (`-1/2`), instead of clap's "unexpected argument '-1'".
    #[arg(long, value_name = "I/N", allow_hyphen_values = true)]
    shard: Option<irad::bench::suite::Shard>,
    /// Check the suite and list its runs (of this shard) without rendering anything.
    #[arg(long)]
    list: bool,
    /// Only render (or find in the cache) the references of the suite's scenes, the
    /// scenes of shard I/N when --shard is given: a pre-pass before a sharded sweep.
    #[arg(long)]
    references_only: bool,
}

/// Runs (or lists) a suite.
pub fn run(options: &ContextOptions, args: SuiteArgs) -> Result<()> {
    let SuiteArgs {
        suite,
        quick,
        out,
        cache,
        shard,
        list,
        references_only,
    } = args;
    let path = suite_path(suite, quick)?;
    let suite = Suite::load(&path)?;
    let shard = shard.unwrap_or(Shard::WHOLE);
    let out = out.unwrap_or_else(|| suite::default_out(&suite, shard));
    if list {
        print_list(&suite, &path, shard);
        return Ok(());
    }
    let ctx = Context::new(options)?;
    let planned = suite.shard(shard).len();
    println!(
        "suite {} ({}): {} of {} runs on {} scenes{}, {} warm-up + {} timed renders each, on {}",
        suite.name,
        path.display(),
        planned,
        suite.runs.len(),
        suite.scenes.len(),
        shard_note(shard),
        suite.warmup,
        suite.repeats,
        device_line(ctx.info())
    );
    let mut progress = Progress::new(&suite, shard, &out);
    // Ctrl-C: stop after the run under way, with everything written; a second Ctrl-C quits
    // at once, but never in the middle of writing the outputs.
    static STOP: AtomicBool = AtomicBool::new(false);
    stop_on_interrupt(&STOP, progress.overall.clone())?;
    let options = SuiteOptions {
        out: out.clone(),
        cache,
        shard,
        stop: Some(&STOP),
        references_only,
    };
    let results = suite::run(&ctx, &suite, &options, |event| progress.show(event))?;
    progress.close();
    report_end(&results, &out, &STOP)
}

/// Picks the suite file: the one named, or with `--quick` the built-in quick suite, which
/// must be there.
fn suite_path(suite: Option<PathBuf>, quick: bool) -> Result<PathBuf> {
    Ok(match suite {
        Some(p) => p,
        None if quick => {
            let path = suite::file::quick_suite_path();
            if !path.exists() {
                bail!(
                    "--quick runs {}, from the source tree irad was built in, which is not there: run irad from its checkout or name a suite file",
                    path.display()
                );
            }
            path
        }
        None => bail!("name a suite file or pass --quick"),
    })
}

/// ` (shard I/N)` after a suite's run count, or nothing for the whole suite.
fn shard_note(shard: Shard) -> String {
    if shard == Shard::WHOLE {
        String::new()
    } else {
        format!(" (shard {shard})")
    }
}

/// `--list`: prints the suite's scenes and the runs of this shard, rendering nothing.
fn print_list(suite: &Suite, path: &Path, shard: Shard) {
    let runs = suite.shard(shard);
    println!(
        "suite {} ({}): {} of {} runs{}",
        suite.name,
        path.display(),
        runs.len(),
        suite.runs.len(),
        shard_note(shard)
    );
    for s in &suite.scenes {
        let cam = &s.scene.camera;
        let failing = s
            .scene
            .failure
            .as_ref()
            .map(|f| format!(", expected to fail: {}", f.methods.join(", ")))
            .unwrap_or_default();
        let depth = match s.reference.settings_of::<Reference>() {
            Some(r) if r.max_depth < 64 => format!(" (max_depth {})", r.max_depth),
            _ => String::new(),
        };
        let home = if s.home.is_empty() {
            String::new()
        } else {
            format!(", home of: {}", s.home.join(", "))
        };
        let frames = match &s.frames {
            Some(f) => format!(
                ", animated: frames {}..{} (calibrated on {}), a reference per frame",
                f.start,
                f.end,
                s.calibration_frame().unwrap_or(f.start)
            ),
            None => String::new(),
        };
        println!(
            "  scene {} {}x{}{frames}, reference {} spp{depth}{failing}{home}",
            s.scene.name,
            cam.width,
            cam.height,
            s.reference.samples()
        );
    }
    for r in runs {
        let declined = r
            .method
            .declines(&suite.scenes[r.scene].scene)
            .map(|_| " (declines this scene)")
            .unwrap_or_default();
        println!("  {:>4} {}{declined}", r.index, r.id);
    }
}

/// Installs the Ctrl-C handler: the first sets `stop` and says so above `bar`, a second
/// exits (once the outputs are written).
fn stop_on_interrupt(stop: &'static AtomicBool, bar: ProgressBar) -> Result<()> {
    ctrlc::set_handler(move || {
        if stop.swap(true, Ordering::SeqCst) {
            suite::output::exit_after_writing(130);
        }
        bar.println("interrupted: stopping after the run under way (Ctrl-C again to quit now)");
    })
    .context("installing the Ctrl-C handler")
}

/// What the screen shows while a suite runs: the bars, the time-left estimate and the runs
/// recorded so far.
struct Progress<'a> {
    suite: &'a Suite,
    out: &'a Path,
    /// This shard's runs.
    plan: Vec<&'a RunSpec>,
    bars: MultiProgress,
    overall: ProgressBar,
    current: ProgressBar,
    eta: Eta,
    /// When the run under way rendered its first frame.
    run_start: Option<Instant>,
    /// Runs recorded so far, kept ones included: what is left is the plan less these.
    recorded: Vec<usize>,
}

impl<'a> Progress<'a> {
    /// Sets up the bars (the suite's runs, the step under way) and sends log lines above them.
    fn new(suite: &'a Suite, shard: Shard, out: &'a Path) -> Self {
        let plan = suite.shard(shard);
        let bars = MultiProgress::new();
        super::logger::on_screen(Some(super::logger::Bars::Several(bars.clone())));
        let overall = bars.add(ProgressBar::new(plan.len() as u64));
        overall.set_style(
            ProgressStyle::with_template(
                "suite [{bar:30}] {pos}/{len} runs, {elapsed} elapsed{msg}",
            )
            .expect("static template")
            .progress_chars("=> "),
        );
        let current = bars.add(ProgressBar::new(1));
        current.set_style(
            ProgressStyle::with_template("  {msg} [{bar:20}] {pos}/{len}")
                .expect("static template")
                .progress_chars("=> "),
        );
        Progress {
            suite,
            out,
            plan,
            bars,
            overall,
            current,
            eta: Eta::default(),
            run_start: None,
            recorded: Vec::new(),
        }
    }

    /// Shows one event of the suite run.
    fn show(&mut self, event: Event) {
        match event {
            Event::StaleLock { holder } => {
                self.bars.suspend(|| {
                    eprintln!(
                        "note: {} was locked by {holder}, which is no longer running (interrupted?): taking it over",
                        self.out.display()
                    )
                });
            }
            Event::Resumed { kept, of } => {
                self.overall.set_position(kept.len() as u64);
                self.bars.suspend(|| {
                    println!(
                        "resuming the interrupted run in {}: {} of {of} runs recorded there are kept (remove the folder to start over)",
                        self.out.display(),
                        kept.len()
                    )
                });
                self.recorded = kept;
            }
            Event::Reference {
                scene,
                done,
                total,
                cached,
            } => {
                self.current.set_length(total as u64);
                self.current.set_position(done as u64);
                self.current.set_message(format!(
                    "{scene}: reference{}",
                    if cached { " (cached)" } else { "" }
                ));
            }
            Event::Render {
                id,
                render,
                renders,
                done,
                total,
                ..
            } => {
                if self.run_start.is_none() {
                    self.run_start = Some(Instant::now());
                }
                self.current.set_length(total as u64);
                self.current.set_position(done as u64);
                self.current.set_message(match renders {
                    0 => format!("{id}: calibration render {}", render + 1),
                    _ => format!("{id}: render {}/{renders}", render + 1),
                });
            }
            Event::Finished { run, record, .. } => self.finished(run, record),
        }
    }

    /// A run is recorded: moves the bar, updates the time-left estimate and prints its line.
    fn finished(&mut self, run: usize, record: &RunRecord) {
        self.overall.set_position(run as u64);
        self.recorded.push(record.index);
        // Only rendered runs teach the estimate, from their first render on (a
        // scene's reference comes before it).
        let spec = self.plan.iter().find(|s| s.index == record.index);
        if let (Status::Ok, Some(start), Some(spec)) = (record.status, self.run_start.take(), spec)
        {
            self.eta
                .finished(self.suite, spec, start.elapsed().as_secs_f64());
        }
        self.run_start = None;
        let left: Vec<_> = self
            .plan
            .iter()
            .filter(|s| !self.recorded.contains(&s.index))
            .copied()
            .collect();
        if let Some(left) = self.eta.left(self.suite, &left) {
            self.overall
                .set_message(format!(", about {} left", indicatif::HumanDuration(left)));
        }
        let line = run_line(record);
        self.bars.suspend(|| println!("{line}"));
    }

    /// Clears the bars and gives the log its plain lines back.
    fn close(self) {
        self.overall.finish_and_clear();
        self.current.finish_and_clear();
        super::logger::on_screen(None);
    }
}

/// The line printed for a recorded run: its times and errors, or its status and note.
fn run_line(record: &RunRecord) -> String {
    match record.status {
        Status::Ok => {
            let m = record.metrics.expect("ok runs are scored");
            format!(
                "{:<48} GPU {:>9} ms  relMSE {:.3e}  bias {:>6.2}%  outliers {:.3}%{}{}",
                record.id,
                record
                    .gpu_ms
                    .map(|t| format!("{t:.2}"))
                    .unwrap_or("-".into()),
                m.rel_mse,
                100.0 * m.bias,
                100.0 * m.outliers,
                if record.pareto { "  *" } else { "" },
                match (record.budget_missed, record.time_ms) {
                    (true, Some(t)) => format!("  time budget of {t} ms missed"),
                    _ => String::new(),
                }
            )
        }
        s => format!("{:<48} {}: {}", record.id, s.as_str(), record.note),
    }
}

/// After the suite: says where the outputs are, exits 130 when interrupted, and fails when
/// a run failed.
fn report_end(results: &SuiteResults, out: &Path, stop: &AtomicBool) -> Result<()> {
    let errors = results
        .runs
        .iter()
        .filter(|r| r.status == Status::Error)
        .count();
    println!(
        "wrote {} (results.csv, results.json, charts/, images/)",
        out.join("report.md").display()
    );
    let refused: std::collections::BTreeSet<&str> = results
        .runs
        .iter()
        .filter(|r| r.status == Status::Refused)
        .map(|r| r.scene.as_str())
        .collect();
    if !refused.is_empty() {
        println!(
            "this device cannot hold {} scene(s), whose runs are recorded as refused: {}",
            refused.len(),
            refused.into_iter().collect::<Vec<_>>().join(", ")
        );
    }
    if stop.load(Ordering::SeqCst) {
        eprintln!(
            "interrupted: {} of {} runs recorded; the outputs hold them, marked incomplete (the same command resumes)",
            results.runs.len(),
            results.runs_planned
        );
        std::process::exit(130);
    }
    if errors > 0 {
        bail!("{errors} run(s) failed; their errors are in the report");
    }
    Ok(())
}
