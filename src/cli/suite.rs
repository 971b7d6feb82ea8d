//! `irad bench suite`: runs a suite with its progress bars, Ctrl-C handling and run lines.

use std::path::PathBuf;

use anyhow::{bail, Context as _, Result};
use indicatif::{ProgressBar, ProgressStyle};

use irad::gpu::{Context, ContextOptions};
use irad::methods::Method;

use super::device_line;

#[derive(clap::Args)]
pub struct SuiteArgs {
    /// Suite TOML file (format in README, "Benchmark suites"); scenes/failure/suite.toml
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
    use irad::bench::suite::{self, Event, Shard, Status, Suite, SuiteOptions};
    let SuiteArgs {
        suite,
        quick,
        out,
        cache,
        shard,
        list,
        references_only,
    } = args;
    let path = match suite {
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
    };
    let suite = Suite::load(&path)?;
    let shard = shard.unwrap_or(Shard::WHOLE);
    let out = out.unwrap_or_else(|| suite::default_out(&suite, shard));
    if list {
        let runs = suite.shard(shard);
        println!(
            "suite {} ({}): {} of {} runs{}",
            suite.name,
            path.display(),
            runs.len(),
            suite.runs.len(),
            if shard == Shard::WHOLE {
                String::new()
            } else {
                format!(" (shard {shard})")
            }
        );
        for s in &suite.scenes {
            let cam = &s.scene.camera;
            let failing = s
                .scene
                .failure
                .as_ref()
                .map(|f| format!(", expected to fail: {}", f.methods.join(", ")))
                .unwrap_or_default();
            let depth = match &s.reference {
                Method::Reference(r) if r.max_depth < 64 => format!(" (max_depth {})", r.max_depth),
                _ => String::new(),
            };
            let home = if s.home.is_empty() {
                String::new()
            } else {
                format!(", home of: {}", s.home.join(", "))
            };
            println!(
                "  scene {} {}x{}, reference {} spp{depth}{failing}{home}",
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
        if shard == Shard::WHOLE {
            String::new()
        } else {
            format!(" (shard {shard})")
        },
        suite.warmup,
        suite.repeats,
        device_line(ctx.info())
    );
    let bars = indicatif::MultiProgress::new();
    super::logger::on_screen(Some(super::logger::Bars::Several(bars.clone())));
    let overall = bars.add(ProgressBar::new(planned as u64));
    overall.set_style(
        ProgressStyle::with_template("suite [{bar:30}] {pos}/{len} runs, {elapsed} elapsed{msg}")
            .expect("static template")
            .progress_chars("=> "),
    );
    let current = bars.add(ProgressBar::new(1));
    current.set_style(
        ProgressStyle::with_template("  {msg} [{bar:20}] {pos}/{len}")
            .expect("static template")
            .progress_chars("=> "),
    );
    // Ctrl-C: stop after the run under way, with everything written; a second Ctrl-C quits
    // at once, but never in the middle of writing the outputs.
    static STOP: std::sync::atomic::AtomicBool = std::sync::atomic::AtomicBool::new(false);
    let stop_bar = overall.clone();
    ctrlc::set_handler(move || {
        if STOP.swap(true, std::sync::atomic::Ordering::SeqCst) {
            suite::output::exit_after_writing(130);
        }
        stop_bar
            .println("interrupted: stopping after the run under way (Ctrl-C again to quit now)");
    })
    .context("installing the Ctrl-C handler")?;
    let options = SuiteOptions {
        out: out.clone(),
        cache,
        shard,
        stop: Some(&STOP),
        references_only,
    };
    let plan = suite.shard(shard);
    let mut eta = suite::eta::Eta::default();
    let mut run_start: Option<std::time::Instant> = None;
    // Runs recorded so far, kept ones included: what is left is the plan less these.
    let mut recorded: Vec<usize> = Vec::new();
    let results = suite::run(&ctx, &suite, &options, |event| match event {
        Event::StaleLock { holder } => {
            bars.suspend(|| {
                eprintln!(
                    "note: {} was locked by {holder}, which is no longer running (interrupted?): taking it over",
                    out.display()
                )
            });
        }
        Event::Resumed { kept, of } => {
            overall.set_position(kept.len() as u64);
            bars.suspend(|| {
                println!(
                    "resuming the interrupted run in {}: {} of {of} runs recorded there are kept (remove the folder to start over)",
                    out.display(),
                    kept.len()
                )
            });
            recorded = kept;
        }
        Event::Reference {
            scene,
            done,
            total,
            cached,
        } => {
            current.set_length(total as u64);
            current.set_position(done as u64);
            current.set_message(format!(
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
            if run_start.is_none() {
                run_start = Some(std::time::Instant::now());
            }
            current.set_length(total as u64);
            current.set_position(done as u64);
            current.set_message(match renders {
                0 => format!("{id}: calibration render {}", render + 1),
                _ => format!("{id}: render {}/{renders}", render + 1),
            });
        }
        Event::Finished { run, record, .. } => {
            overall.set_position(run as u64);
            recorded.push(record.index);
            // Only rendered runs teach the estimate, from their first render on (a
            // scene's reference comes before it).
            let spec = plan.iter().find(|s| s.index == record.index);
            if let (Status::Ok, Some(start), Some(spec)) = (record.status, run_start.take(), spec) {
                eta.finished(&suite, spec, start.elapsed().as_secs_f64());
            }
            run_start = None;
            let left: Vec<_> = plan
                .iter()
                .filter(|s| !recorded.contains(&s.index))
                .copied()
                .collect();
            if let Some(left) = eta.left(&suite, &left) {
                overall.set_message(format!(", about {} left", indicatif::HumanDuration(left)));
            }
            let line =
                match record.status {
                    Status::Ok => {
                        let m = record.metrics.expect("ok runs are scored");
                        format!(
                        "{:<48} GPU {:>9} ms  relMSE {:.3e}  bias {:>6.2}%  outliers {:.3}%{}{}",
                        record.id,
                        record.gpu_ms.map(|t| format!("{t:.2}")).unwrap_or("-".into()),
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
                };
            bars.suspend(|| println!("{line}"));
        }
    })?;
    overall.finish_and_clear();
    current.finish_and_clear();
    super::logger::on_screen(None);
    let errors = results
        .runs
        .iter()
        .filter(|r| r.status == Status::Error)
        .count();
    println!(
        "wrote {} (results.csv, results.json, charts/, images/)",
        out.join("report.md").display()
    );
    if STOP.load(std::sync::atomic::Ordering::SeqCst) {
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
