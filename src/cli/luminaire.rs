//! `irad luminaire generate`: a light-field luminaire from an analytic near-field emitter.

use std::path::PathBuf;

use anyhow::{Context as _, Result};
use clap::Subcommand;

use super::{parse_size_up_to, progress};
use irad::scene::luminaire::emitters::{MAX_GRID, MAX_IMAGE_RESOLUTION};

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
    #[arg(long, value_parser = |s: &str| parse_size_up_to(s, MAX_GRID), default_value = "11x9")]
    grid: (u32, u32),
    /// Texels per image, WxH (the thesis: 256x256).
    #[arg(long, value_parser = |s: &str| parse_size_up_to(s, MAX_IMAGE_RESOLUTION), default_value = "64x64")]
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

fn generate_luminaire(args: &GenerateArgs) -> Result<()> {
    use irad::scene::luminaire::emitters::{available_memory, EmitterKind, GenerateOptions};
    use irad::scene::luminaire::Basis;
    let options = GenerateOptions {
        emitter: match args.emitter {
            EmitterArg::Disk => EmitterKind::Disk,
            EmitterArg::Headlight => EmitterKind::Headlight,
            EmitterArg::Reflector => EmitterKind::Reflector,
        },
        grid: args.grid,
        resolution: args.resolution,
        basis: match args.basis {
            BasisArg::Bilinear => Basis::Bilinear,
            BasisArg::QuadraticBspline => Basis::QuadraticBSpline,
        },
        radius: args.radius,
        radiance: args.radiance,
        facet: args.facet,
        beam: args.beam,
        spread: args.spread,
        frames: args.frames,
        sweep: args.sweep,
        delta: args.delta,
        image_size: args.image_size,
    };
    options.check(available_memory(), |w| log::warn!("{w}"))?;
    // The folder first, so a bad --out fails before the minutes of generation.
    std::fs::create_dir_all(&args.out)
        .with_context(|| format!("--out {}: cannot create the folder", args.out.display()))?;
    let bar = progress(u64::from(args.frames), "luminaire generate");
    let luminaire = options.generate(|| bar.inc(1))?;
    bar.finish_and_clear();
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
        args.grid.0,
        args.grid.1,
        args.resolution.0,
        args.resolution.1
    );
    Ok(())
}

/// Runs a luminaire command.
pub fn run(command: LuminaireCommand) -> Result<()> {
    match command {
        LuminaireCommand::Generate(args) => generate_luminaire(&args),
    }
}
