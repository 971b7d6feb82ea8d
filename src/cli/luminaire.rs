//! `irad luminaire generate`: a light-field luminaire from an analytic near-field emitter.

use std::path::PathBuf;

use anyhow::{Context as _, Result};
use clap::Subcommand;

use super::{parse_size, progress};

#[derive(Subcommand)]
pub enum LuminaireCommand {
    /// Build a luminaire from an analytic near-field emitter and write OUT/luminaire.toml
    /// and OUT/images.exr. Each image at a texel is the emitter's radiance averaged over its
    /// basis function's support, times delta^2 / |s - u_m|^4 (Eq. 4.1 at the node).
    Generate(GenerateArgs),
}

#[derive(clap::Args)]
pub struct GenerateArgs {
    /// disk: a uniform Lambertian disk (on its axis the irradiance has a closed form);
    /// headlight: a ringed reflector disk with a lobe tilted down and a cut-off line;
    /// reflector: a faceted reflector with a cut-off, each facet throwing a narrow beam
    /// its own way (--facet, --beam, --spread).
    #[arg(long, value_enum, default_value_t = EmitterArg::Headlight)]
    emitter: EmitterArg,
    /// Basis functions on the filter plane, WxH (the thesis's car headlight: 11x9).
    #[arg(long, value_parser = parse_size, default_value = "11x9")]
    grid: (u32, u32),
    /// Texels per image, WxH (the thesis: 256x256).
    #[arg(long, value_parser = parse_size, default_value = "64x64")]
    resolution: (u32, u32),
    #[arg(long, value_enum, default_value_t = BasisArg::QuadraticBspline)]
    basis: BasisArg,
    /// The emitter's radius in metres; the basis grid spans it.
    #[arg(long, default_value_t = 0.06)]
    radius: f64,
    /// The emitter's peak radiance.
    #[arg(long, default_value_t = 20.0)]
    radiance: f64,
    /// reflector: the facets' side, metres.
    #[arg(long, default_value_t = 0.012)]
    facet: f64,
    /// reflector: each facet's beam width (Gaussian standard deviation), degrees.
    #[arg(long, default_value_t = 2.0)]
    beam: f64,
    /// reflector: the facets aim within +-spread degrees horizontally and up to spread
    /// degrees down.
    #[arg(long, default_value_t = 30.0)]
    spread: f64,
    /// Write a sequence of this many atlases (images_000.exr, ...; atlas = "images_*.exr"),
    /// the beam lowered by --sweep over them (a levelling headlight: the tables are rebuilt
    /// every frame of a render). headlight and reflector only.
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..=256))]
    frames: u32,
    /// With --frames: how many degrees the beam is lowered from the first atlas to the last.
    #[arg(long, default_value_t = 0.0)]
    sweep: f64,
    /// The image plane's distance from the filter plane, metres.
    #[arg(long, default_value_t = 0.05)]
    delta: f64,
    /// The images' extent on the image plane, metres (square).
    #[arg(long, default_value_t = 0.3)]
    image_size: f64,
    /// Output folder.
    #[arg(short, long)]
    out: PathBuf,
}

#[derive(Clone, Copy, clap::ValueEnum)]
enum EmitterArg {
    Disk,
    Headlight,
    Reflector,
}

#[derive(Clone, Copy, clap::ValueEnum)]
enum BasisArg {
    Bilinear,
    QuadraticBspline,
}

/// Memory available to a new allocation (Linux: /proc/meminfo MemAvailable), when known.
fn available_memory() -> Option<u64> {
    let text = std::fs::read_to_string("/proc/meminfo").ok()?;
    let line = text.lines().find(|l| l.starts_with("MemAvailable:"))?;
    let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib * 1024)
}

fn generate_luminaire(args: &GenerateArgs) -> Result<()> {
    use irad::scene::luminaire::{Basis, Emitter, Geometry, Luminaire};
    let positive = |name: &str, x: f64| {
        anyhow::ensure!(
            x.is_finite() && x > 0.0,
            "--{name} {x}: must be finite and > 0"
        );
        Ok(())
    };
    let (grid, resolution, radius, radiance, delta) = (
        args.grid,
        args.resolution,
        args.radius,
        args.radiance,
        args.delta,
    );
    positive("radius", radius)?;
    positive("radiance", radiance)?;
    positive("delta", delta)?;
    positive("image-size", args.image_size)?;
    positive("facet", args.facet)?;
    positive("beam", args.beam)?;
    positive("spread", args.spread)?;
    anyhow::ensure!(
        grid.0 <= 64 && grid.1 <= 64 && resolution.0 <= 4096 && resolution.1 <= 4096,
        "--grid at most 64x64 and --resolution at most 4096x4096"
    );
    // Sizes up front (issue 22 item 1d): the renderer holds each atlas as one storage buffer of
    // 16 bytes a texel (at most 4 GiB on any device, 128 MiB guaranteed), and generation holds
    // every frame's images in memory at 12 bytes a texel, twice while writing.
    let texels = u64::from(grid.0 * grid.1) * u64::from(resolution.0) * u64::from(resolution.1);
    // A sequence's atlases share one buffer (lightfield/tables.rs), beside the current frame's;
    // generation holds every frame's images, the first twice for a sequence, and one atlas.
    let frames = u64::from(args.frames);
    let gpu_bytes = texels * 16 * if frames > 1 { frames } else { 1 };
    let host_bytes = texels * 12 * (frames + 1 + u64::from(frames > 1));
    let gib = |b: u64| b as f64 / (1u64 << 30) as f64;
    anyhow::ensure!(
        gpu_bytes <= u64::from(u32::MAX),
        "--grid {}x{} --resolution {}x{} --frames {}: {texels} texels an atlas, a {:.1} GiB \
         buffer on the GPU, over the 4 GiB any Vulkan device binds as one storage buffer (fewer \
         images, texels or frames)",
        grid.0,
        grid.1,
        resolution.0,
        resolution.1,
        args.frames,
        gib(gpu_bytes)
    );
    if let Some(available) = available_memory() {
        anyhow::ensure!(
            host_bytes <= available,
            "--grid {}x{} --resolution {}x{} --frames {}: generating needs {:.1} GiB of memory, \
             over the {:.1} GiB available",
            grid.0,
            grid.1,
            resolution.0,
            resolution.1,
            args.frames,
            gib(host_bytes),
            gib(available)
        );
    }
    if gpu_bytes > 1 << 27 {
        eprintln!(
            "warning: the atlas is a {:.2} GiB buffer on the GPU, over the 128 MiB every Vulkan \
             device binds (maxStorageBufferRange; `irad info` shows a device's)",
            gib(gpu_bytes)
        );
    }
    let grid = [grid.0 as usize, grid.1 as usize];
    // The grid spans the emitter's diameter (a single node sits at its centre).
    let pitch = |n: usize| {
        if n > 1 {
            2.0 * radius / (n - 1) as f64
        } else {
            2.0 * radius
        }
    };
    let geometry = Geometry {
        grid,
        pitch: [pitch(grid[0]), pitch(grid[1])],
        basis: match args.basis {
            BasisArg::Bilinear => Basis::Bilinear,
            BasisArg::QuadraticBspline => Basis::QuadraticBSpline,
        },
        delta,
        image_size: [args.image_size, args.image_size],
        resolution: [resolution.0 as usize, resolution.1 as usize],
    };
    let emitter = match args.emitter {
        EmitterArg::Disk => Emitter::Disk { radius, radiance },
        EmitterArg::Headlight => Emitter::Headlight {
            radius,
            radiance,
            sharpness: 12.0,
            tilt: 3.0,
        },
        EmitterArg::Reflector => Emitter::Reflector {
            radius,
            radiance,
            facet: args.facet,
            beam: args.beam,
            spread: args.spread,
            tilt: 0.0,
        },
    };
    anyhow::ensure!(
        args.sweep.is_finite() && args.sweep.abs() <= 45.0,
        "--sweep {}: must be finite and within +-45 degrees",
        args.sweep
    );
    let tilts: Vec<f64> = (0..args.frames)
        .map(|f| args.sweep * f as f64 / (args.frames.max(2) - 1) as f64)
        .collect();
    let emitters = tilts
        .iter()
        .map(|&t| emitter.tilted(t))
        .collect::<Option<Vec<Emitter>>>()
        .filter(|_| args.frames > 1)
        .map_or_else(
            || {
                anyhow::ensure!(
                    args.frames == 1,
                    "--frames {}: the disk does not change; a sequence needs --emitter headlight or reflector",
                    args.frames
                );
                Ok(vec![emitter])
            },
            Ok,
        )?;
    // The folder first, so a bad --out fails before the minutes of generation.
    std::fs::create_dir_all(&args.out)
        .with_context(|| format!("--out {}: cannot create the folder", args.out.display()))?;
    let bar = progress(emitters.len() as u64, "luminaire generate");
    let mut frames: Vec<Luminaire> = emitters
        .iter()
        .map(|e| {
            let l = Luminaire::from_emitter(
                geometry,
                |u, s| e.radiance(u, s, delta),
                &format!("{e:?}"),
            );
            bar.inc(1);
            l
        })
        .collect();
    bar.finish_and_clear();
    let mut luminaire = frames.remove(0);
    if !frames.is_empty() {
        luminaire.sequence = std::iter::once(luminaire.images.clone())
            .chain(frames.into_iter().map(|l| l.images))
            .collect();
    }
    let path = luminaire.write(&args.out)?;
    println!(
        "wrote {} and {} ({}x{} images of {}x{} texels)",
        path.display(),
        if args.frames > 1 {
            format!(
                "{} atlases {}",
                args.frames,
                args.out.join("images_*.exr").display()
            )
        } else {
            args.out.join("images.exr").display().to_string()
        },
        grid[0],
        grid[1],
        resolution.0,
        resolution.1
    );
    Ok(())
}

/// Runs a luminaire command.
pub fn run(command: LuminaireCommand) -> Result<()> {
    match command {
        LuminaireCommand::Generate(args) => generate_luminaire(&args),
    }
}
