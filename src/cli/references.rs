//! `irad bench references`: renders or extends the converged references of a suite's scenes
//! (irad::bench::suite::converged), one per frame of an animated scene (the suite's `frames`),
//! with a progress bar per reference and Ctrl-C handling; `--shard I/N` takes a share of the
//! frames for a batch scheduler.

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

use anyhow::{bail, Context as _, Result};

use irad::bench::suite::converged::{self, ExtendOptions, Progress, TARGET_REL_MSE};
use irad::bench::suite::{Shard, Suite};
use irad::gpu::{Context, ContextOptions};
use irad::methods::Renderers;
use irad::scene::gpu::GpuScene;

use super::{device_line, progress};

#[derive(clap::Args)]
pub struct ReferencesArgs {
    /// Suite TOML file: its scenes at its resolution, with its reference settings.
    suite: PathBuf,
    /// Only these scenes (by name, as the suite lists them; repeat the flag for several).
    /// Default: every scene of the suite.
    #[arg(long = "scene", value_name = "NAME")]
    scenes: Vec<String>,
    /// Stop a scene once its net relMSE, estimated from its two halves, is at most this.
    #[arg(long, default_value_t = TARGET_REL_MSE, value_parser = parse_target)]
    target: f64,
    /// Stop a scene after this many minutes of this run, an animated scene's frames all
    /// together (the chunk under way finishes); the same command later goes on where it
    /// stopped. Default: no limit.
    #[arg(long, value_parser = parse_minutes)]
    minutes: Option<f64>,
    /// Samples per pixel of one chunk: a chunk is saved as soon as it is rendered, so an
    /// interruption loses at most one.
    #[arg(long, default_value_t = 256, value_parser = clap::value_parser!(u32).range(1..=65536))]
    chunk_spp: u32,
    /// Render part I (0-based) of N, for a batch scheduler: frame f of an animated scene
    /// belongs to part f mod N, a still scene to part (its index in the suite) mod N. Parts
    /// write different folders, so they may run at once; each resumes on its own.
    #[arg(long, value_name = "I/N", default_value = "0/1")]
    shard: Shard,
}

fn parse_target(s: &str) -> Result<f64, String> {
    match s.parse::<f64>() {
        Ok(v) if v > 0.0 && v.is_finite() => Ok(v),
        _ => Err(format!(
            "{s}: the target relMSE is a number above 0 (such as 0.01)"
        )),
    }
}

/// A relMSE to three significant digits, in scientific notation below 0.001: targets go far
/// under the 1e-4 that four decimals can show.
fn figure(v: f64) -> String {
    if v == 0.0 || !v.is_finite() {
        format!("{v}")
    } else if (1e-3..1e4).contains(&v.abs()) {
        let decimals = (2 - v.abs().log10().floor() as i32).max(0) as usize;
        format!("{v:.decimals$}")
    } else {
        format!("{v:.2e}")
    }
}

fn parse_minutes(s: &str) -> Result<f64, String> {
    match s.parse::<f64>() {
        Ok(v) if v > 0.0 && v <= 7.0 * 24.0 * 60.0 => Ok(v),
        _ => Err(format!(
            "{s}: minutes are a number above 0 and at most a week (10080)"
        )),
    }
}

/// The note for a lock whose holder is gone.
fn took_over(dir: &Path, holder: &str) -> String {
    format!(
        "note: {} was locked by {holder}, which is no longer running (interrupted?): taking it over",
        dir.display()
    )
}

pub fn run(options: &ContextOptions, args: ReferencesArgs) -> Result<()> {
    let suite = Suite::load(&args.suite)?;
    let known: Vec<&str> = suite.scenes.iter().map(|s| s.scene.name.as_str()).collect();
    if let Some(bad) = args.scenes.iter().find(|n| !known.contains(&n.as_str())) {
        bail!(
            "{}: no scene named {bad} (its scenes: {})",
            args.suite.display(),
            known.join(", ")
        );
    }
    let shard = args.shard;
    // (scene, frame) of every reference of this shard: a still scene's one, an animated
    // scene's one per frame of the suite's `frames`.
    let mut jobs = Vec::new();
    for (i, s) in suite.scenes.iter().enumerate() {
        if !(args.scenes.is_empty() || args.scenes.contains(&s.scene.name)) {
            continue;
        }
        match &s.frames {
            Some(frames) => jobs.extend(
                frames
                    .clone()
                    .filter(|f| *f as usize % shard.count == shard.index)
                    .map(|f| (s, Some(f))),
            ),
            None if i % shard.count == shard.index => jobs.push((s, None)),
            None => {}
        }
    }
    let part = if shard == Shard::WHOLE {
        String::new()
    } else {
        format!(" (shard {shard})")
    };
    if jobs.is_empty() {
        println!(
            "{}{part}: no reference to render: this shard has no still scene and no frame of the chosen scenes",
            args.suite.display()
        );
        return Ok(());
    }
    let ctx = Context::new(options)?;
    println!(
        "{} converged reference(s) of {}{part} to a net relMSE of {}, chunks of {} spp, on {}",
        jobs.len(),
        args.suite.display(),
        figure(args.target),
        args.chunk_spp,
        device_line(ctx.info())
    );
    static STOP: AtomicBool = AtomicBool::new(false);
    ctrlc::set_handler(|| {
        if STOP.swap(true, Ordering::SeqCst) {
            std::process::exit(130);
        }
        eprintln!("\ninterrupted: stopping after the chunk under way (Ctrl-C again to quit now; at most that chunk is lost)");
    })
    .context("installing the Ctrl-C handler")?;
    let renderers = Renderers::default();
    // --minutes holds for a scene, all its frames together, from its first job.
    let mut deadlines: std::collections::HashMap<String, Instant> = Default::default();
    for (suite_scene, frame) in jobs {
        if STOP.load(Ordering::SeqCst) {
            break;
        }
        let scene = &suite_scene.scene;
        let cam = &scene.camera;
        let name = match frame {
            Some(f) => format!("{} frame {f}", scene.name),
            None => scene.name.clone(),
        };
        let extend = ExtendOptions {
            target_rel_mse: args.target,
            deadline: args.minutes.map(|m| {
                *deadlines
                    .entry(scene.name.clone())
                    .or_insert_with(|| Instant::now() + Duration::from_secs_f64(60.0 * m))
            }),
            chunk_spp: args.chunk_spp,
            stop: Some(&STOP),
        };
        let bar = progress(1, &format!("{name} {}x{}", cam.width, cam.height));
        let mut chunk_base = 0u64;
        let on = |event: Progress| match event {
            Progress::Rendering { done, .. } => bar.set_position(chunk_base + done as u64),
            Progress::Saved { record, ms_per_spp } => {
                // Bar: samples so far against those the target needs (relMSE falls
                // as 1 / samples).
                let spp = record.total_spp();
                let needed = record
                    .rel_mse
                    .map_or(2 * spp, |e| (spp as f64 * e / args.target).ceil() as u64);
                bar.set_length(needed.max(spp + 1));
                bar.set_position(spp);
                chunk_base = spp;
                bar.set_message(format!(
                    "spp, relMSE {}, {:.1} ms GPU/spp",
                    record.rel_mse.map_or("-".into(), figure),
                    ms_per_spp
                ));
            }
            Progress::StaleLock { dir, holder } => {
                bar.suspend(|| eprintln!("{}", took_over(dir, &holder)))
            }
        };
        let result = match frame {
            Some(f) => converged::extend_frame(
                &ctx,
                &renderers,
                scene,
                f,
                &suite_scene.reference,
                &extend,
                on,
            ),
            None => GpuScene::upload(&ctx, scene)
                .with_context(|| format!("uploading {}", scene.name))
                .and_then(|gpu_scene| {
                    converged::extend(
                        &ctx,
                        &renderers,
                        scene,
                        &gpu_scene,
                        &suite_scene.reference,
                        &extend,
                        on,
                    )
                }),
        };
        bar.finish_and_clear();
        super::logger::on_screen(None);
        let done = result?;
        let r = &done.record;
        let reached = r.rel_mse.is_some_and(|e| e <= args.target);
        println!(
            "{name}: {} spp, net relMSE {} (target {} {}), {:.0} s GPU in all; {}",
            r.total_spp(),
            r.rel_mse.map_or("-".into(), figure),
            figure(args.target),
            if reached {
                "reached"
            } else {
                "not reached yet: the same command goes on"
            },
            r.gpu_ms / 1000.0,
            done.dir.join("reference.json").display()
        );
    }
    if STOP.load(Ordering::SeqCst) {
        std::process::exit(130);
    }
    Ok(())
}
