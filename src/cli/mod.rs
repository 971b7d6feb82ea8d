//! The `irad` command line: one module per command; this one parses and dispatches.

mod bench;
mod compare;
mod export;
mod info;
mod logger;
mod luminaire;
mod method_flags;
mod methods;
mod references;
mod render;
mod selfcheck;
mod sequence;
mod shader_tree;
mod shaders;
mod suite;

use std::process::ExitCode;

use anyhow::Result;
use clap::{Parser, Subcommand};
use indicatif::{ProgressBar, ProgressStyle};

use irad::gpu::{Context, ContextOptions, DeviceInfo, DeviceSelector, Validation};

/// irad: many-light and light-source importance sampling, as Vulkan compute kernels.
///
/// Environment: IRAD_DEVICE stands for --device when the flag is not given; IRAD_VALIDATE=1
/// turns on the Khronos validation layer (as --validate does); IRAD_FORCE_STAGING=1 puts
/// every buffer behind staging copies, as on a discrete GPU. A switch takes 1, true or yes
/// (on) or 0, false, no or empty (off); any other value is an error. IRAD_VULKAN_LIBRARY
/// names a Vulkan loader to use instead of the system's libvulkan.so.1.
#[derive(Parser)]
#[command(name = "irad", version, about, long_about)]
struct Cli {
    /// Device to run on: an index or part of a name, as `irad info` lists them (also
    /// IRAD_DEVICE). Default: the first discrete GPU, else integrated, else virtual, else CPU
    /// (lavapipe).
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
    /// Render a scene and write <OUT>.exr (float32 linear RGB), <OUT>.png (tone-mapped sRGB)
    /// and <OUT>.json (method, parameters, device, per-pass GPU times, metrics).
    ///
    /// With no scene, renders the Cornell box built into irad. The method's settings are
    /// flags (`irad methods METHOD` lists them with their defaults); a flag the chosen method
    /// does not take is an error.
    Render(render::RenderArgs),
    /// Score an image against a reference (two EXRs of one size, or two folders of frames
    /// from `irad render --sequence`): relMSE, RMSE, bias, outliers, Lab error, NaN/Inf and
    /// HDR-FLIP, and with -o the error maps as PNGs with colour bars and the figures as JSON.
    Compare(compare::CompareArgs),
    /// List the methods, or one method's settings with their defaults and ranges: the flags
    /// of `irad render --method NAME` and the keys of a suite file's `params`.
    Methods(methods::MethodsArgs),
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
    Bench(bench::Bench),
    /// Light-field luminaires (Lu 14 ch. 4; format in docs/methods/lightfield.md).
    #[command(subcommand)]
    Luminaire(luminaire::LuminaireCommand),
    /// Write a scene for another renderer, to cross-check irad's images there.
    #[command(subcommand)]
    Export(export::ExportCommand),
}

/// `irad methods | head` closes the pipe early: like other command-line tools, irad then ends
/// quietly (SIGPIPE's default action) instead of panicking in `println!` on EPIPE. irad
/// writes to no socket, where that default would matter.
fn quiet_on_closed_pipe() {
    #[cfg(unix)]
    // SAFETY: restores a signal's default disposition at startup, before any thread exists.
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
}

pub fn main() -> ExitCode {
    quiet_on_closed_pipe();
    logger::install();
    let cli = match Cli::try_parse() {
        Ok(cli) => cli,
        Err(e) => {
            let args: Vec<String> = std::env::args().collect();
            if let (true, Some(tip)) = (e.use_stderr(), method_flags::switch_tip(&args)) {
                let _ = e.print();
                eprintln!("{tip}");
                return ExitCode::from(2);
            }
            e.exit()
        }
    };
    match run(cli) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::FAILURE
        }
    }
}

fn run(mut cli: Cli) -> Result<()> {
    // IRAD_DEVICE stands for --device when the flag is not given (scripts/gpu-check.sh; the
    // tests read it too).
    // Every variable is checked, whether or not its flag is given: a bad value is an error.
    let mut options = ContextOptions::from_env()?;
    if cli.device.is_some() {
        options.device = cli.device.clone();
    }
    cli.device = options.device.clone();
    if cli.validate {
        options.validation = Validation::On;
    }
    match cli.command {
        Command::Info => info::info(cli.device.as_ref()),
        Command::Render(args) => render::run(&options, args),
        Command::Methods(args) => methods::run(&args),
        Command::Compare(args) => compare::run(args),
        Command::Selfcheck => info::selfcheck(&Context::new(&options)?),
        Command::Shaders { check } => shaders::run(check),
        Command::Luminaire(command) => luminaire::run(command),
        Command::Export(command) => export::run(command),
        Command::Bench(command) => bench::run(&options, command),
    }
}

/// An image size, `WIDTHxHEIGHT`, each in 1..=`irad::scene::MAX_RESOLUTION` (as in scene
/// and suite files).
pub(crate) fn parse_size(s: &str) -> Result<(u32, u32), String> {
    parse_size_up_to(s, irad::scene::MAX_RESOLUTION)
}

/// `WIDTHxHEIGHT`, each in 1..=max.
pub(crate) fn parse_size_up_to(s: &str, max: u32) -> Result<(u32, u32), String> {
    let bad = || format!("`{s}`: expected WIDTHxHEIGHT, each in 1..={max}");
    let (w, h) = s.split_once('x').ok_or_else(bad)?;
    let parse = |t: &str| {
        t.trim()
            .parse::<u32>()
            .ok()
            .filter(|v| (1..=max).contains(v))
    };
    Ok((parse(w).ok_or_else(bad)?, parse(h).ok_or_else(bad)?))
}

/// A progress bar for `what`, which log lines are printed around until the next bar.
pub(crate) fn progress(len: u64, what: &str) -> ProgressBar {
    let bar = ProgressBar::new(len);
    logger::on_screen(Some(logger::Bars::One(bar.clone())));
    bar.set_style(
        ProgressStyle::with_template(&format!(
            "{what} [{{bar:30}}] {{pos}}/{{len}} ({{elapsed}} elapsed, {{eta}} left) {{msg}}"
        ))
        .expect("static template")
        .progress_chars("=> "),
    );
    bar
}

/// Loads the scene file at `path` under a spinner naming it (a large mesh takes seconds).
pub(crate) fn load_scene(
    path: &std::path::Path,
    camera: Option<usize>,
) -> anyhow::Result<irad::scene::Scene> {
    let spinner = ProgressBar::new_spinner();
    logger::on_screen(Some(logger::Bars::One(spinner.clone())));
    spinner.set_message(format!("loading {}", path.display()));
    spinner.enable_steady_tick(std::time::Duration::from_millis(120));
    let scene = irad::scene::load_with_camera(path, camera);
    spinner.finish_and_clear();
    logger::on_screen(None);
    Ok(scene?)
}

pub(crate) fn device_line(d: &DeviceInfo) -> String {
    format!(
        "{} ({}, Vulkan {}.{}.{}, {})",
        d.name, d.kind, d.api_version.0, d.api_version.1, d.api_version.2, d.driver
    )
}
