//! The `irad` command line.

use std::process::ExitCode;

use anyhow::{bail, Result};
use clap::{Parser, Subcommand};
use indicatif::{ProgressBar, ProgressStyle};

use irad::bench::scan as scan_bench;
use irad::gpu::{self, Context, ContextOptions, DeviceInfo, DeviceSelector, Validation};
use irad::selfcheck;
use irad::shaders::ShaderTree;

/// irad: many-light and light-source importance sampling, as Vulkan compute kernels.
///
/// Environment: IRAD_VALIDATE=1 turns on the Khronos validation layer (as --validate does);
/// IRAD_VULKAN_LIBRARY names a Vulkan loader to use instead of the system's libvulkan.so.1.
#[derive(Parser)]
#[command(name = "irad", version, about, long_about)]
struct Cli {
    /// Device to run on: an index or part of a name, as `irad info` lists them.
    /// Default: the first discrete GPU, else integrated, else virtual, else CPU (lavapipe).
    #[arg(long, global = true, value_name = "INDEX|NAME")]
    device: Option<DeviceSelector>,

    /// Enable the Khronos validation layer and print its messages (also IRAD_VALIDATE=1).
    #[arg(long, global = true)]
    validate: bool,

    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// List every Vulkan device with the limits irad depends on; the one irad picks is marked.
    Info,
    /// Check the GPU against the CPU: prefix sums of random rows against an f64 scan.
    Selfcheck,
    /// Rebuild spv/ from glsl/ with glslangValidator and check it with spirv-val
    /// (run in a source checkout; the binary embeds spv/ as it was when built).
    Shaders {
        /// Only report which modules are stale, missing or orphaned; change nothing.
        #[arg(long)]
        check: bool,
    },
    /// Benchmarks that measure and print.
    #[command(subcommand)]
    Bench(Bench),
}

#[derive(Subcommand)]
enum Bench {
    /// Prefix-sum GB/s next to a plain copy kernel's GB/s (the bandwidth bound), per size.
    Scan {
        /// Timed repetitions per size (the median is reported), after 3 warm-up runs.
        #[arg(long, default_value_t = 15)]
        repeats: usize,
        /// Sizes as ROW_LENGTH or ROW_LENGTHxROWS, comma separated (default: a set from 2^16
        /// to 6 x 2^20 elements, single rows and batched rows). Elements must be a multiple of 4.
        #[arg(long, value_delimiter = ',', value_parser = parse_case)]
        sizes: Vec<scan_bench::ScanCase>,
    },
    /// Rays/s of the GPU BVH traversal (closest and any hit; camera and random rays) next to
    /// obvhs's CWBVH on the CPU using every core, and the ratio GPU/CPU.
    Rays {
        /// Scene file (default: a displaced sphere of 196608 triangles and 1024 random ones).
        scene: Option<std::path::PathBuf>,
        /// Timed repetitions per case (the median is reported), after 1 warm-up run.
        #[arg(long, default_value_t = 5)]
        repeats: usize,
        /// Number of random (incoherent) rays; camera rays are one per pixel of 1024x768.
        #[arg(long, default_value_t = 1 << 20)]
        rays: usize,
    },
}

fn parse_case(s: &str) -> Result<scan_bench::ScanCase, String> {
    let parse = |t: &str| {
        t.trim()
            .parse::<usize>()
            .map_err(|_| format!("`{s}`: expected ROW_LENGTH or ROW_LENGTHxROWS"))
    };
    let (row_length, row_count) = match s.split_once('x') {
        Some((l, r)) => (parse(l)?, parse(r)?),
        None => (parse(s)?, 1),
    };
    if row_length == 0 || row_count == 0 {
        return Err(format!("`{s}`: sizes must be positive"));
    }
    if row_length
        .checked_mul(row_count)
        .is_none_or(|n| n > u32::MAX as usize)
    {
        return Err(format!("`{s}`: more elements than a u32 can index"));
    }
    Ok(scan_bench::ScanCase {
        row_length,
        row_count,
    })
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    match run(cli) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::FAILURE
        }
    }
}

fn run(cli: Cli) -> Result<()> {
    let validation = if cli.validate {
        Validation::On
    } else {
        Validation::from_env()
    };
    let options = ContextOptions {
        device: cli.device.clone(),
        validation,
    };
    match cli.command {
        Command::Info => info(cli.device.as_ref()),
        Command::Selfcheck => run_selfcheck(&Context::new(&options)?),
        Command::Shaders { check } => shaders(check),
        Command::Bench(Bench::Scan { repeats, sizes }) => {
            let ctx = Context::new(&options)?;
            let cases = if sizes.is_empty() {
                scan_bench::DEFAULT_CASES.to_vec()
            } else {
                sizes
            };
            let bar = progress(cases.len() as u64, "bench scan");
            let mut results = Vec::new();
            for case in cases {
                bar.set_message(format!("{} x {}", case.row_length, case.row_count));
                results.push(scan_bench::run_case(&ctx, case, 3, repeats.max(1))?);
                bar.inc(1);
            }
            bar.finish_and_clear();
            scan_bench::print_table(&device_line(ctx.info()), &results);
            Ok(())
        }
        Command::Bench(Bench::Rays {
            scene,
            repeats,
            rays,
        }) => {
            use irad::bvh::procedural;
            if let Some(path) = scene {
                bail!("{}: scene loading not wired yet", path.display());
            }
            let ctx = Context::new(&options)?;
            let triangles = procedural::noisy_sphere(1, 128, 1024);
            let bounds = procedural::bounds(&triangles);
            let camera = procedural::camera_for_bounds(bounds, 1024, 768);
            let camera_rays = procedural::camera_rays(&camera);
            let random_rays = procedural::random_rays(2, bounds, rays);
            let report =
                irad::bench::rays::run(&ctx, &triangles, &camera_rays, &random_rays, repeats)?;
            irad::bench::rays::print_table(&device_line(ctx.info()), &report);
            Ok(())
        }
    }
}

fn progress(len: u64, what: &str) -> ProgressBar {
    let bar = ProgressBar::new(len);
    bar.set_style(
        ProgressStyle::with_template(&format!("{what} [{{bar:30}}] {{pos}}/{{len}} {{msg}}"))
            .expect("static template")
            .progress_chars("=> "),
    );
    bar
}

fn device_line(d: &DeviceInfo) -> String {
    format!(
        "{} ({}, Vulkan {}.{}.{}, {})",
        d.name, d.kind, d.api_version.0, d.api_version.1, d.api_version.2, d.driver
    )
}

fn info(selector: Option<&DeviceSelector>) -> Result<()> {
    let devices = gpu::list_devices()?;
    let chosen = gpu::device_info::choose(&devices, selector);
    println!(
        "Vulkan devices ({} found; * marks the one irad uses):",
        devices.len()
    );
    for d in &devices {
        let mark = if chosen.as_ref().ok() == Some(&d.index) {
            "*"
        } else {
            " "
        };
        let mib = |b: u64| b as f64 / (1024.0 * 1024.0);
        println!("{mark} {}: {}", d.index, device_line(d));
        println!(
            "    max storage buffer range   {} bytes ({:.0} MiB)",
            d.max_storage_buffer_range,
            mib(d.max_storage_buffer_range)
        );
        println!(
            "    shared memory / workgroup  {} bytes",
            d.max_compute_shared_memory
        );
        println!(
            "    workgroup                  {} invocations, size {:?}, count {:?}",
            d.max_workgroup_invocations, d.max_workgroup_size, d.max_workgroup_count
        );
        println!(
            "    subgroup size              {} (arithmetic in compute: {})",
            d.subgroup_size,
            yes_no(d.subgroup_arithmetic)
        );
        println!(
            "    f32 atomic add (buffers)   {}",
            yes_no(d.float_atomic_add)
        );
        match d.compute_queue_family {
            Some(family) if d.timestamps() => println!(
                "    timestamps                 yes ({} valid bits, {} ns per tick, queue family {family})",
                d.timestamp_valid_bits, d.timestamp_period_ns
            ),
            Some(family) => println!("    timestamps                 no (queue family {family}): passes get wall-clock times only"),
            None => println!("    compute queue              none: irad cannot use this device"),
        }
        println!(
            "    push constants             {} bytes",
            d.max_push_constants
        );
        println!(
            "    device-local memory        {:.0} MiB (largest heap)",
            mib(d.device_local_heap)
        );
    }
    chosen?;
    Ok(())
}

fn yes_no(b: bool) -> &'static str {
    if b {
        "yes"
    } else {
        "no"
    }
}

fn run_selfcheck(ctx: &Context) -> Result<()> {
    println!("selfcheck on {}", device_line(ctx.info()));
    let mut failed = 0;
    for &(row_length, row_count) in selfcheck::SCAN_CASES {
        let c = selfcheck::check_scan(ctx, row_length, row_count, 1)?;
        println!(
            "  prefix sum {:>8} x {:<5} max relative error {:.2e} (row totals {:.2e}), tolerance {:.0e}: {}",
            c.row_length,
            c.row_count,
            c.max_relative_error,
            c.max_total_error,
            selfcheck::SCAN_TOLERANCE,
            if c.passed() { "ok" } else { "FAILED" }
        );
        failed += usize::from(!c.passed());
    }
    let log = ctx.validation_log().messages();
    if !log.is_empty() {
        bail!("{} validation message(s), printed above", log.len());
    }
    if failed > 0 {
        bail!("{failed} prefix-sum check(s) over tolerance");
    }
    println!("selfcheck passed");
    Ok(())
}

fn shaders(check: bool) -> Result<()> {
    let tree = ShaderTree::source_checkout();
    if check {
        let problems = tree.check()?;
        if problems.is_empty() {
            println!(
                "spv/ is in sync with glsl/ ({} kernels)",
                tree.kernel_names()?.len()
            );
            return Ok(());
        }
        for p in &problems {
            println!("{p}");
        }
        bail!("spv/ is out of sync with glsl/: run `irad shaders` (or `cargo run -- shaders`)");
    }
    let built = tree.rebuild()?;
    println!(
        "built and validated {} kernels into {}: {}",
        built.len(),
        tree.spv_dir().display(),
        built.join(", ")
    );
    println!("rebuild irad (cargo build) to embed them");
    Ok(())
}
