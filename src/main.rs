//! The `irad` command line.

use irad::methods::direct::MAX_DIRECT_SPP;
use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::{bail, Context as _, Result};
use clap::{Parser, Subcommand};
use indicatif::{ProgressBar, ProgressStyle};

use irad::bench::scan as scan_bench;
use irad::gpu::{self, Context, ContextOptions, DeviceInfo, DeviceSelector, Validation};
use irad::methods::bundles::directions::DirectionDensity;
use irad::methods::bundles::light_vertices::LightSelection;
use irad::methods::bundles::{BundlesSettings, Strategy as BundlesStrategy, Suppression};
use irad::methods::compensation::{ClampSettings, VplClamp};
use irad::methods::envmap::{EnvSettings, Strategy as EnvStrategy};
use irad::methods::gbuffer::PixelSampling;
use irad::methods::ir::schedule::Absorption;
use irad::methods::ir::{DirectLight, IrSettings};
use irad::methods::lightfield::{LightfieldSettings, Strategy as LightfieldStrategy};
use irad::methods::rebuild::TableRebuild;
use irad::methods::reference::ReferenceSettings;
use irad::methods::Method;
use irad::render::{self, RenderJob};
use irad::scene;
use irad::selfcheck;
use irad::shaders::ShaderTree;

/// irad: many-light and light-source importance sampling, as Vulkan compute kernels.
///
/// Environment: IRAD_VALIDATE=1 turns on the Khronos validation layer (as --validate does);
/// IRAD_VULKAN_LIBRARY names a Vulkan loader to use instead of the system's libvulkan.so.1.
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
    /// With no scene, renders the Cornell box built into irad.
    Render(RenderArgs),
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
    /// Light-field luminaires (Lu 14 ch. 4; format in README "Light-field luminaires").
    #[command(subcommand)]
    Luminaire(LuminaireCommand),
}

#[derive(Subcommand)]
enum LuminaireCommand {
    /// Build a luminaire from an analytic near-field emitter and write OUT/luminaire.toml
    /// and OUT/images.exr. Each image at a texel is the emitter's radiance averaged over its
    /// basis function's support, times delta^2 / |s - u_m|^4 (Eq. 4.1 at the node).
    Generate(GenerateArgs),
}

#[derive(clap::Args)]
struct GenerateArgs {
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

#[derive(clap::Args)]
struct SuiteArgs {
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
    #[arg(long, value_name = "I/N")]
    shard: Option<irad::bench::suite::Shard>,
    /// Check the suite and list its runs (of this shard) without rendering anything.
    #[arg(long)]
    list: bool,
    /// Only render (or find in the cache) the references of the suite's scenes, the
    /// scenes of shard I/N when --shard is given: a pre-pass before a sharded sweep.
    #[arg(long)]
    references_only: bool,
}

#[derive(clap::Args)]
struct RenderArgs {
    /// Scene TOML file (DESIGN.md "Scene files"); default: the embedded Cornell box.
    scene: Option<PathBuf>,
    /// Rendering method.
    #[arg(long, value_enum, default_value_t = MethodArg::Reference)]
    method: MethodArg,
    /// Samples per pixel (reference: one path per pixel per frame; env: N_s per frame, light
    /// and BRDF samples together).
    #[arg(long, default_value_t = 64, value_parser = clap::value_parser!(u32).range(1..))]
    spp: u32,
    /// ir, bir, bundles, env: frames, each with fresh VPLs (light samples for env) and fresh
    /// subpixel positions.
    #[arg(long, default_value_t = 16, value_parser = clap::value_parser!(u32).range(1..))]
    frames: u32,
    /// ir: paths started on the lights per frame (Keller's N; about N / (1 - mean albedo)
    /// VPLs). bir: VPLs per frame, standard and reverse together.
    #[arg(long, default_value_t = 256, value_parser = clap::value_parser!(u32).range(1..=1 << 20))]
    vpls: u32,
    /// ir: fractional absorption, floor(rho^j N) paths reach vertex j (Keller's, for stills;
    /// where that reaches 0 the last paths go on by Russian roulette, so no path length is
    /// lost), or Russian roulette at every vertex (for animation).
    #[arg(long, value_enum, default_value_t = AbsorptionArg::Fractional)]
    absorption: AbsorptionArg,
    /// ir, bir: clamp the VPL gather's geometry term cos cos / d^2 at b (Keller's weak
    /// singularity: no spikes next to VPLs). "auto" [default]: b = N / A for N surface VPLs
    /// per frame over the scene's area A (pi VPLs expected within 1 / sqrt(b) of a point);
    /// a number sets b; 0 leaves the term unclamped. The clamp used is in the JSON's stats.
    #[arg(long, default_value = "auto", value_parser = parse_clamp)]
    clamp: VplClamp,
    /// env, bundles, lightfield: build the sampling tables derived from the map or atlas (cube
    /// map and CDFs, latitude-longitude table, pyramid, bundle directions, luminaire tables)
    /// once for a still input and per frame for a sequence, or every frame as Lu 14's dynamic
    /// pipeline does (for timing it; the same image bits for a still input).
    #[arg(long, value_enum, default_value_t = RebuildArg::WhenChanged)]
    rebuild_tables: RebuildArg,
    /// ir, bir, bundles: with a clamp (ir, bir: --clamp; bundles: --two-bounce-clamp), add
    /// back exactly what it removed by short paths from the shading point (bundles: from the
    /// bundle hit x2; Kollig and Keller 2004; unbiased) [default: on], or leave the clamp's
    /// bias (off).
    #[arg(long, value_enum, default_value_t = OnOff::On)]
    compensate: OnOff,
    /// ir, bir, bundles: direct-light samples per pixel and frame, each from its own camera
    /// ray at a new subpixel position, so direct light and the pixel footprint get this many
    /// samples per expensive frame while the VPL gather shades one position [default: see
    /// README "Budgets"].
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=MAX_DIRECT_SPP as i64))]
    direct_spp: Option<u32>,
    /// ir: interleaved sampling over k x k pixel blocks (1 disables it).
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..=16))]
    interleave: u32,
    /// ir: direct light by next-event estimation (as the reference) or by the light vertices
    /// as VPLs (Keller's original).
    #[arg(long, value_enum, default_value_t = DirectArg::Nee)]
    direct: DirectArg,
    /// bir: which VPLs are shaded: standard (from the lights), reverse (from the camera) or
    /// both [default]. bundles: which one-bounce paths: through the VPLs (vpl), through the
    /// ray bundles (bundle), or both combined by MIS (mis) [default]. env: how the map's light
    /// is sampled: dynamic [default], uniform-faces, alpha, latlong, hierarchical, brdf or
    /// cosine.
    #[arg(long, value_enum)]
    strategy: Option<StrategyArg>,
    /// env: texels along a side of each face of the cube map that drives the light samples
    /// (built from the map once, or per frame for a sequence: --rebuild-tables).
    #[arg(long, default_value_t = 256, value_parser = clap::value_parser!(u32).range(1..=4096))]
    face_resolution: u32,
    /// env --strategy dynamic|uniform-faces: take every sample from the cube map (Lu Eq. 3.5,
    /// the thesis's Fig. 3.6 setting) instead of half from the BRDF (Eq. 3.7).
    #[arg(long)]
    light_only: bool,
    /// env --strategy dynamic|uniform-faces: round(M_f) light samples per face, each of weight
    /// 1, instead of the beta weights (the thesis's integer counts, Fig. 3.9).
    #[arg(long)]
    integer_counts: bool,
    /// env --strategy alpha: M, the samples per pixel and frame, half light and half BRDF,
    /// that estimate the per-pixel split alpha (Lu 14 Eq. 5.4-5.5); the other --spp minus M
    /// use it [default: half of --spp].
    #[arg(long, value_parser = clap::value_parser!(u32).range(0..=65536))]
    alpha_samples: Option<u32>,
    /// lightfield: K_max, the most samples per pixel, frame and image (Lu's Fig. 4.11).
    #[arg(long, default_value_t = 64, value_parser = clap::value_parser!(u32).range(1..=65536))]
    k_max: u32,
    /// lightfield: invert the CDFs by binary search instead of Lu's modified secant search.
    #[arg(long)]
    binary_search: bool,
    /// lightfield: every pixel takes the same Halton prefixes (Lu Section 4.5.3) instead of
    /// its own rotation of them (biased per pixel pattern, not in the mean). env: every pixel
    /// takes the frame's one set of light samples per face (Lu's) instead of its own window
    /// of a 64 times longer sequence (the whole image's error then moves as one).
    #[arg(long)]
    shared_samples: bool,
    /// lightfield: one shadow ray per image toward its median point instead of one per sample
    /// (Lu Section 4.5.2's approximation; biased at shadow edges).
    #[arg(long)]
    averaged_visibility: bool,
    /// env, lightfield: no shadow rays (every sample counted as visible), as in the thesis's
    /// timings; for timing comparisons only: the image is wrong wherever light is occluded.
    #[arg(long)]
    no_shadows: bool,
    /// bundles: iterations per frame, each one VPL and one global ray bundle (the paper's 21).
    #[arg(long, default_value_t = 21, value_parser = clap::value_parser!(u32).range(1..=65536))]
    iterations: u32,
    /// bundles: the MIS weights of the one-bounce paths: the balance heuristic (the paper's)
    /// or the power heuristic (exponent 2).
    #[arg(long, value_enum, default_value_t = HeuristicArg::Balance)]
    heuristic: HeuristicArg,
    /// bundles: shade the two-bounce paths (x0, x1, x2, x3) through the VPL-to-bundle-hit
    /// edge (Tokuyoshi Eq. 7-8).
    #[arg(long, value_enum, default_value_t = OnOff::On)]
    two_bounce: OnOff,
    /// bundles: clamp the two-bounce paths' x1-x2 geometry term cos cos / d^2 at b (the
    /// paper's clamp, 10 there; compensated by default, see --compensate, else a bias). "auto"
    /// [default]: b = N / A for N light vertices per frame over the scene's area A, as --clamp;
    /// a number sets b; 0 leaves the term unclamped. The b used is in the JSON's stats.
    #[arg(long, default_value = "auto", value_parser = parse_clamp)]
    two_bounce_clamp: VplClamp,
    /// bundles: glossy spike suppression of the one-bounce paths (Tokuyoshi Section 5, each a
    /// named bias): clamp the Phong exponent per sample by the density of samples around it
    /// (roughness), clamp each path's contribution (clamp), or none.
    #[arg(long, value_enum, default_value_t = GlossyArg::Roughness)]
    glossy: GlossyArg,
    /// bundles --glossy roughness: the paper's m' (neighbours per kernel; larger blurs more).
    #[arg(long, default_value_t = 16.0)]
    roughness_m: f32,
    /// bundles --glossy clamp: the largest channel a path's contribution may have.
    #[arg(long, default_value_t = 1.0)]
    contribution_clamp: f32,
    /// bundles: the lights each iteration's VPLs leave from: one VPL from every point and spot
    /// light (all, the paper's default), or one light chosen by power (roulette, for many
    /// lights; Tokuyoshi Section 4.1).
    #[arg(long, value_enum, default_value_t = LightsArg::All)]
    lights: LightsArg,
    /// bundles: the density of the bundle directions: uniform on the sphere, or, in a scene
    /// with an environment map, Tokuyoshi's Eq. 2 (Le(w) + Le(-w) + 2 Lo), which importance
    /// samples the map's direct light (the default there).
    #[arg(long, value_enum, default_value_t = DirectionsArg::Environment)]
    directions: DirectionsArg,
    /// bundles --directions environment: Eq. 2's offset Lo (luminance) for the indirect light
    /// the map does not show [default: 0 when the map is the only light, else the map's mean
    /// luminance].
    #[arg(long)]
    env_offset: Option<f32>,
    /// bir: camera points per frame the reverse VPLs start from (the M of Segovia's Eq. 7).
    #[arg(long, default_value_t = 50, value_parser = clap::value_parser!(u32).range(1..=65536))]
    pool: u32,
    /// bir: next-event samples per reverse VPL for its outgoing radiance.
    #[arg(long, default_value_t = 4, value_parser = clap::value_parser!(u32).range(1..=1024))]
    light_samples: u32,
    /// bir: standard VPLs each bounce from a reverse VPL connects to for its radiance (drawn
    /// uniformly, weighted; 0: every one).
    #[arg(long, default_value_t = 0)]
    connections: u32,
    /// bir: vertices the paths from a reverse VPL go on for (next-event estimation at each)
    /// before they connect to the standard VPLs.
    #[arg(long, default_value_t = 3, value_parser = clap::value_parser!(u32).range(1..=64))]
    depth: u32,
    /// bir: candidates per kept VPL (the paper's resampling ratio r); 0 shades every
    /// candidate, no resampling.
    #[arg(long, default_value_t = 10)]
    ratio: u32,
    /// bir: the resampling CDF's uniform floor, a fraction of the mean candidate power (1:
    /// half the draws uniform over the candidates; 0: none, which darkens the image where
    /// powers are underestimated: Segovia Fig. 3).
    #[arg(long, default_value_t = 1.0)]
    floor: f32,
    /// bir: camera points per candidate for its power estimate.
    #[arg(long, default_value_t = 5, value_parser = clap::value_parser!(u32).range(1..=1024))]
    power_samples: u32,
    /// bir: candidates resampled together (0: the whole frame's), so storage stays
    /// O(batch + kept VPLs).
    #[arg(long, default_value_t = 0)]
    batch: u32,
    /// bir: choose the lights that start light paths by their power instead of by their
    /// measured contribution to what the camera sees (Segovia Section 4.1).
    #[arg(long)]
    light_cdf_off: bool,
    /// bir --strategy both: keep the paper's fixed 1/2 side weights instead of weights that
    /// follow how often each side brought more camera power in earlier batches.
    #[arg(long)]
    fixed_weights: bool,
    /// Seed of every random and quasi-random number: same seed, same device, same bits
    /// (0..=4294967295).
    #[arg(long, default_value_t = 0, allow_hyphen_values = true, value_parser = parse_seed)]
    seed: u32,
    /// Most scattering events per path (a safety cap: Russian roulette ends paths first).
    #[arg(long, default_value_t = 1024)]
    max_depth: u32,
    /// First bounce at which Russian roulette may end a path.
    #[arg(long, default_value_t = 3)]
    roulette_depth: u32,
    /// reference --max-depth 1: split the direct light between light and BSDF sampling per
    /// pixel by Lu 14 ch. 5's alpha, estimated over the first M frames (one sample of each,
    /// balance heuristic); later frames take 2 alpha BSDF and 2 (1 - alpha) light samples.
    /// Writes OUT.alpha.{exr,png} (red: light, green: BSDF).
    #[arg(long, value_name = "M")]
    alpha_frames: Option<u32>,
    /// Output stem: writes OUT.exr, OUT.png and OUT.json [default: out/<scene name>].
    #[arg(short, long, value_name = "OUT")]
    out: Option<PathBuf>,
    /// Sample every pixel at its centre instead of over its area (no antialiasing): for
    /// comparing methods without pixel-footprint noise (use it for the reference too).
    #[arg(long)]
    pixel_centres: bool,
    /// Exposure of the PNG in stops (the EXR is never tone mapped).
    #[arg(long, default_value_t = 0.0, allow_negative_numbers = true)]
    exposure: f32,
    /// Reference EXR of the same scene and size: adds relMSE, RMSE, Lab error, bias and
    /// outliers against it to the JSON and the summary.
    #[arg(long, value_name = "EXR")]
    reference: Option<PathBuf>,
}

#[derive(Clone, Copy, clap::ValueEnum)]
enum MethodArg {
    /// The unbiased path tracer every accuracy figure is measured against.
    Reference,
    /// Instant radiosity (Keller 97): VPLs from a quasi-random walk from the lights.
    Ir,
    /// Bidirectional instant radiosity (Segovia 06): VPLs from the lights and from the camera.
    Bir,
    /// Real-time bidirectional path tracing (Tokuyoshi 12): VPLs and global ray bundles
    /// combined by MIS, for point and spot lights.
    Bundles,
    /// Environment-map direct light with per-pixel dynamic cube-map sampling (Lu 14 ch. 3).
    Env,
    /// Light-field luminaires' direct light by restricted-CDF sampling (Lu 14 ch. 4).
    Lightfield,
}

#[derive(Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
enum StrategyArg {
    /// bir: standard VPLs only (from the lights).
    Standard,
    /// bir: reverse VPLs only (ends of length-2 camera paths).
    Reverse,
    /// bir: both sides, resampled together.
    Both,
    /// bundles: one-bounce paths through the VPLs only.
    Vpl,
    /// bundles: one-bounce paths through the ray bundles only.
    Bundle,
    /// bundles: both, combined by multiple importance sampling.
    Mis,
    /// env: per-pixel face shares, fractional counts, MIS with BRDF sampling (Lu 14 ch. 3).
    Dynamic,
    /// env: the same with every face getting 1/6 of the light samples.
    UniformFaces,
    /// env: BRDF sampling only.
    Brdf,
    /// env: cosine-weighted hemisphere sampling only.
    Cosine,
    /// env: one table over the whole latitude-longitude map (pbrt, Mitsuba), MIS with BRDF.
    Latlong,
    /// lightfield: Lu's restricted windows, A_m from the summed-area table, K_m by A_m.
    Restricted,
    /// lightfield: uniform over the restricted window.
    Uniform,
    /// lightfield: one CDF over each whole image, no restriction.
    Precomputed,
    /// lightfield: uniform over the whole image plane (the brute-force reference).
    BruteForce,
    /// env: a luminance mip pyramid descended 2x2 per level (Falcor, Mitsuba 3), MIS with BRDF.
    Hierarchical,
    /// env: dynamic's samplers split per pixel by Lu 14 ch. 5's estimated alpha; writes
    /// OUT.alpha.{exr,png} (red: light samples, green: BRDF samples, yellow: half and half).
    Alpha,
}

#[derive(Clone, Copy, clap::ValueEnum)]
enum HeuristicArg {
    Balance,
    Power,
}

#[derive(Clone, Copy, clap::ValueEnum)]
enum GlossyArg {
    None,
    Roughness,
    Clamp,
}

#[derive(Clone, Copy, clap::ValueEnum)]
enum LightsArg {
    All,
    Roulette,
}

#[derive(Clone, Copy, clap::ValueEnum)]
enum DirectionsArg {
    Uniform,
    Environment,
}

#[derive(Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
enum OnOff {
    On,
    Off,
}

#[derive(Clone, Copy, clap::ValueEnum)]
enum AbsorptionArg {
    Fractional,
    Roulette,
}

/// `--clamp`: "auto" or a finite number >= 0.
fn parse_clamp(s: &str) -> Result<VplClamp, String> {
    if s == "auto" {
        return Ok(VplClamp::Auto);
    }
    match s.parse::<f32>() {
        Ok(b) if b.is_finite() && b >= 0.0 => Ok(VplClamp::Fixed(b)),
        _ => Err(format!(
            "expected \"auto\" or a finite number >= 0, got {s:?}"
        )),
    }
}

#[derive(Clone, Copy, clap::ValueEnum)]
enum RebuildArg {
    WhenChanged,
    EveryFrame,
}

#[derive(Clone, Copy, clap::ValueEnum)]
enum DirectArg {
    Nee,
    Vpl,
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
    /// env's per-frame sampling table (cube map, CDFs, light samples) at several cube-face
    /// resolutions, next to the time to copy the map once (the bandwidth bound) and the
    /// latitude-longitude table's build.
    Env {
        /// Scene file with an environment map (default: scenes/glossy-env of the source tree).
        scene: Option<PathBuf>,
        /// Replace the scene's map by a synthetic sky of this size, WIDTHxHEIGHT (the work
        /// depends on the map's size, not its content).
        #[arg(long, value_parser = parse_size)]
        map: Option<(u32, u32)>,
        /// Cube-face resolutions, comma separated.
        #[arg(long, value_delimiter = ',', default_values_t = [64u32, 128, 256, 512, 1024])]
        faces: Vec<u32>,
        /// Light samples per face (N_s / 2).
        #[arg(long, default_value_t = 30)]
        samples: u32,
        /// Timed repetitions per resolution (the median is reported), after 2 warm-up runs.
        #[arg(long, default_value_t = 9)]
        repeats: usize,
        /// Then the shading table: env's frame time at these samples per pixel (N_s), with
        /// and without shadow rays, comma separated; 0 skips it.
        #[arg(long, value_delimiter = ',', default_values_t = [16u32, 60, 240])]
        spp: Vec<u32>,
        /// The strategies of the shading table, comma separated.
        #[arg(long, value_delimiter = ',', default_values_t = ["dynamic".to_string(), "alpha".into(), "latlong".into(), "hierarchical".into()])]
        strategies: Vec<String>,
        /// The shading table's image size, WIDTHxHEIGHT (default: the scene's).
        #[arg(long, value_parser = parse_size)]
        resolution: Option<(u32, u32)>,
        /// The shading table's timed frames per row (after one warm-up frame).
        #[arg(long, default_value_t = 4, value_parser = clap::value_parser!(u32).range(1..))]
        frames: u32,
    },
    /// lightfield's per-frame breakdown (Lu 14 Fig. 4.12: G-buffer, A estimation, sampling,
    /// shading, shadow rays) for each strategy and sample budget K, with the frame rate and
    /// the samples actually drawn per lit pixel. Time against error: `irad bench suite
    /// scenes/suites/lightfield-lavapipe.toml` (or lightfield.toml on a GPU).
    Lightfield {
        /// Scene file with luminaires (default: scenes/car-headlights of the source tree, the
        /// thesis's two-headlight car).
        scene: Option<PathBuf>,
        /// K, samples per pixel, luminaire and frame, comma separated (the thesis: 200).
        #[arg(long, value_delimiter = ',', default_values_t = [50u32, 100, 200])]
        spp: Vec<u32>,
        /// The strategies, comma separated.
        #[arg(long, value_delimiter = ',', default_values_t = ["restricted".to_string(), "uniform".into(), "precomputed".into()])]
        strategies: Vec<String>,
        /// K_max, the most samples per pixel, frame and image.
        #[arg(long, default_value_t = 64, value_parser = clap::value_parser!(u32).range(1..=65536))]
        k_max: u32,
        /// Image size, WIDTHxHEIGHT (default: the scene's; the thesis: 1024x768).
        #[arg(long, value_parser = parse_size)]
        resolution: Option<(u32, u32)>,
        /// Timed frames per render (after a one-frame warm-up).
        #[arg(long, default_value_t = 4, value_parser = clap::value_parser!(u32).range(1..))]
        frames: u32,
        /// Timed renders of each kind (the median is reported).
        #[arg(long, default_value_t = 3, value_parser = clap::value_parser!(u32).range(1..))]
        repeats: u32,
    },
    /// Instant radiosity's per-pass GPU times for a range of VPL budgets, and its gathering
    /// throughput in (pixel, VPL) pairs/s next to the scene's incoherent any-hit ray rate.
    Ir {
        /// Scene file (default: the embedded Cornell box).
        scene: Option<PathBuf>,
        /// Paths per frame (Keller's N), comma separated.
        #[arg(long, value_delimiter = ',', default_values_t = [64u32, 256, 1024, 4096])]
        vpls: Vec<u32>,
        /// Frames rendered per budget (the mean per frame is reported), after a warm-up.
        #[arg(long, default_value_t = 3, value_parser = clap::value_parser!(u32).range(1..))]
        frames: u32,
        /// Interleaved sampling k.
        #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..=16))]
        interleave: u32,
        /// Random rays for the any-hit ray rate.
        #[arg(long, default_value_t = 1 << 18)]
        rays: usize,
    },
    /// Run a benchmark suite: every method at every budget on every scene, timed (median of
    /// repeats after a warm-up) and scored against each scene's cached reference. Writes
    /// results.csv, results.json, charts/<scene>.svg (relMSE against GPU time, log-log) and
    /// report.md (tables, Pareto-optimal runs, thumbnails and error maps) into the output
    /// folder, rewritten after every run, so an interrupted suite leaves readable results.
    Suite(SuiteArgs),
    /// Merge the output folders of a suite's shards into one set of results, charts and report.
    Merge {
        /// Output folders of `irad bench suite --shard`.
        #[arg(required = true)]
        parts: Vec<PathBuf>,
        /// Merged output folder.
        #[arg(short, long, value_name = "DIR")]
        out: PathBuf,
        /// Merge parts measured on different devices, drivers or irad versions (refused by
        /// default: their GPU times are not comparable). Charts then get a line per method
        /// and device, and Pareto marks are per device.
        #[arg(long)]
        allow_mixed_devices: bool,
    },
    /// Rays/s of the GPU BVH traversal (closest and any hit; camera and random rays) next to
    /// obvhs's CWBVH on the CPU using every core, and the ratio GPU/CPU.
    Rays {
        /// Scene file: its triangles, its camera at 1024x768 (default: a displaced sphere of
        /// 196608 triangles and 1024 random ones).
        scene: Option<std::path::PathBuf>,
        /// Timed repetitions per case (the median is reported), after 1 warm-up run.
        #[arg(long, default_value_t = 5)]
        repeats: usize,
        /// Number of random (incoherent) rays; camera rays are one per pixel of 1024x768.
        #[arg(long, default_value_t = 1 << 20)]
        rays: usize,
    },
}

fn parse_size(s: &str) -> Result<(u32, u32), String> {
    let bad = || format!("`{s}`: expected WIDTHxHEIGHT, each in 1..=16384");
    let (w, h) = s.split_once('x').ok_or_else(bad)?;
    let parse = |t: &str| {
        t.trim()
            .parse::<u32>()
            .ok()
            .filter(|v| (1..=16384).contains(v))
    };
    Ok((parse(w).ok_or_else(bad)?, parse(h).ok_or_else(bad)?))
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

/// A seed: any whole number 0..=4294967295. Negative values are taken as values (not flags) so
/// that `--seed -1` gets this message rather than clap's tip to write `-- -1`.
fn parse_seed(text: &str) -> Result<u32, String> {
    match text.trim().parse::<i128>() {
        Ok(v) if (0..=i128::from(u32::MAX)).contains(&v) => Ok(v as u32),
        Ok(_) => Err("seeds are whole numbers 0..=4294967295".into()),
        Err(_) => Err("not a whole number (seeds are 0..=4294967295)".into()),
    }
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

fn run(mut cli: Cli) -> Result<()> {
    // IRAD_DEVICE stands for --device when the flag is not given (scripts/gpu-check.sh; the
    // tests read it too).
    if cli.device.is_none() {
        if let Ok(value) = std::env::var("IRAD_DEVICE") {
            if !value.trim().is_empty() {
                cli.device = Some(
                    value
                        .parse()
                        .map_err(|e| anyhow::anyhow!("IRAD_DEVICE={value}: {e}"))?,
                );
            }
        }
    }
    let validation = if cli.validate {
        Validation::On
    } else {
        Validation::from_env()
    };
    let options = ContextOptions {
        device: cli.device.clone(),
        validation,
        force_staging: ContextOptions::force_staging_from_env(),
    };
    match cli.command {
        Command::Info => info(cli.device.as_ref()),
        Command::Render(args) => render(&options, args),
        Command::Selfcheck => run_selfcheck(&Context::new(&options)?),
        Command::Shaders { check } => shaders(check),
        Command::Luminaire(LuminaireCommand::Generate(args)) => generate_luminaire(&args),
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
        Command::Bench(Bench::Env {
            scene,
            map,
            faces,
            samples,
            repeats,
            spp,
            strategies,
            resolution,
            frames,
        }) => {
            let path = scene.unwrap_or_else(|| {
                PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("scenes/glossy-env/scene.toml")
            });
            let mut scene = scene::load(&path)?;
            if let Some((w, h)) = map {
                scene.environment = Some(irad::bench::env::synthetic_sky(w, h));
            }
            anyhow::ensure!(
                faces.iter().all(|&r| (1..=4096).contains(&r)),
                "--faces: each resolution must be in 1..=4096"
            );
            let ctx = Context::new(&options)?;
            let bar = progress(faces.len() as u64, "bench env");
            let results = irad::bench::env::run(
                &ctx,
                &scene,
                &faces,
                samples.max(1),
                2,
                repeats.max(1),
                |r| {
                    bar.set_message(format!("R = {r}"));
                    bar.inc(1);
                },
            )?;
            bar.finish_and_clear();
            let map = scene.environment.as_ref().expect("checked by run");
            irad::bench::env::print_table(&device_line(ctx.info()), map, samples.max(1), &results);
            let spp: Vec<u32> = spp.into_iter().filter(|&n| n > 0).collect();
            if spp.is_empty() {
                return Ok(());
            }
            let strategies =
                strategies_by_name(&strategies, &EnvStrategy::ALL, |s| s.name(), "env")?;
            if let Some((w, h)) = resolution {
                scene.camera.width = w;
                scene.camera.height = h;
            }
            let bar = progress(
                (strategies.len() * spp.len() * 2) as u64,
                "bench env shading",
            );
            let face_resolution = 256;
            let shading = irad::bench::env::run_shading(
                &ctx,
                &scene,
                &strategies,
                &spp,
                face_resolution,
                frames,
                |s, n, shadows| {
                    bar.set_message(format!(
                        "{} N_s {n}{}",
                        s.name(),
                        if shadows { "" } else { " no shadows" }
                    ));
                    bar.inc(1);
                },
            )?;
            bar.finish_and_clear();
            println!();
            irad::bench::env::print_shading(&device_line(ctx.info()), &scene, &shading);
            Ok(())
        }
        Command::Bench(Bench::Ir {
            scene,
            vpls,
            frames,
            interleave,
            rays,
        }) => {
            let scene = match scene {
                Some(path) => scene::load(&path)?,
                None => scene::default_scene(),
            };
            let ctx = Context::new(&options)?;
            let bar = progress(vpls.len() as u64 + 2, "bench ir");
            let report =
                irad::bench::ir::run(&ctx, &scene, &vpls, frames, interleave, rays, |what| {
                    bar.set_message(what.to_string());
                    bar.inc(1);
                })?;
            bar.finish_and_clear();
            irad::bench::ir::print_table(
                &device_line(ctx.info()),
                &render::scene_label(&scene),
                scene.camera.width,
                scene.camera.height,
                &report,
            );
            Ok(())
        }
        Command::Bench(Bench::Lightfield {
            scene,
            spp,
            strategies,
            k_max,
            resolution,
            frames,
            repeats,
        }) => {
            let path = scene.unwrap_or_else(|| {
                PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("scenes/car-headlights/scene.toml")
            });
            let mut scene = scene::load(&path)?;
            if let Some((w, h)) = resolution {
                scene.camera.width = w;
                scene.camera.height = h;
            }
            anyhow::ensure!(
                !spp.is_empty() && spp.iter().all(|&k| (1..=65536).contains(&k)),
                "--spp: each K must be in 1..=65536"
            );
            let strategies = strategies_by_name(
                &strategies,
                &LightfieldStrategy::ALL,
                |s| s.name(),
                "lightfield",
            )?;
            let ctx = Context::new(&options)?;
            let bar = progress((strategies.len() * spp.len()) as u64, "bench lightfield");
            let results = irad::bench::lightfield::run(
                &ctx,
                &scene,
                &strategies,
                &spp,
                k_max,
                frames,
                repeats as usize,
                |s, k| {
                    bar.set_message(format!("{} K {k}", s.name()));
                    bar.inc(1);
                },
            )?;
            bar.finish_and_clear();
            irad::bench::lightfield::print(
                &device_line(ctx.info()),
                &scene,
                k_max,
                frames,
                &results,
            );
            Ok(())
        }
        Command::Bench(Bench::Suite(args)) => bench_suite(&options, args),
        Command::Bench(Bench::Merge {
            parts,
            out,
            allow_mixed_devices,
        }) => {
            let merged = irad::bench::suite::merge::merge(&parts, &out, allow_mixed_devices)?;
            println!(
                "merged {} parts: {} of {} runs of suite {}{}",
                parts.len(),
                merged.runs.len(),
                merged.runs_in_suite,
                merged.suite,
                if merged.complete {
                    ""
                } else {
                    " (incomplete: some runs are missing)"
                }
            );
            println!("wrote {}", out.join("report.md").display());
            Ok(())
        }
        Command::Bench(Bench::Rays {
            scene,
            repeats,
            rays,
        }) => {
            use irad::bvh::procedural;
            // A scene's own camera at 1024x768, or a camera framing the procedural mesh.
            let (triangles, camera) = match scene {
                Some(path) => {
                    let scene = scene::load(&path)?;
                    let triangles: Vec<_> = scene.triangles.iter().map(|t| t.positions).collect();
                    let camera = irad::scene::Camera {
                        width: 1024,
                        height: 768,
                        ..scene.camera
                    };
                    (triangles, camera)
                }
                None => {
                    let triangles = procedural::noisy_sphere(1, 128, 1024);
                    let camera =
                        procedural::camera_for_bounds(procedural::bounds(&triangles), 1024, 768);
                    (triangles, camera)
                }
            };
            let bounds = procedural::bounds(&triangles);
            let ctx = Context::new(&options)?;
            let camera_rays = procedural::camera_rays(&camera);
            let random_rays = procedural::random_rays(2, bounds, rays);
            let report =
                irad::bench::rays::run(&ctx, &triangles, &camera_rays, &random_rays, repeats)?;
            irad::bench::rays::print_table(&device_line(ctx.info()), &report);
            Ok(())
        }
    }
}

fn render(options: &ContextOptions, args: RenderArgs) -> Result<()> {
    let scene = match &args.scene {
        Some(path) => scene::load(path)?,
        None => scene::default_scene(),
    };
    for w in &scene.warnings {
        eprintln!("warning: {w}");
    }
    let ctx = Context::new(options)?;
    let pixels = if args.pixel_centres {
        PixelSampling::Centres
    } else {
        PixelSampling::Jittered
    };
    if let Some(m) = args.alpha_frames {
        if !matches!(args.method, MethodArg::Reference) || args.max_depth != 1 {
            bail!("--alpha-frames {m}: splits the reference's direct light only (--method reference --max-depth 1)");
        }
    }
    let method = match args.method {
        MethodArg::Reference => Method::Reference(ReferenceSettings {
            spp: args.spp,
            seed: args.seed,
            max_depth: args.max_depth,
            roulette_depth: args.roulette_depth,
            alpha_frames: args.alpha_frames,
            pixels,
        }),
        MethodArg::Ir => Method::Ir(IrSettings {
            paths: args.vpls,
            frames: args.frames,
            seed: args.seed,
            absorption: match args.absorption {
                AbsorptionArg::Fractional => Absorption::Fractional,
                AbsorptionArg::Roulette => Absorption::Roulette,
            },
            clamp: ClampSettings {
                clamp: args.clamp,
                compensate: args.compensate == OnOff::On,
            },
            interleave: args.interleave,
            direct: match args.direct {
                DirectArg::Nee => DirectLight::NextEvent,
                DirectArg::Vpl => DirectLight::Vpl,
            },
            direct_spp: args.direct_spp.unwrap_or(IrSettings::default().direct_spp),
            pixels,
        }),
        MethodArg::Bir if !(args.floor.is_finite() && args.floor >= 0.0) => {
            bail!("--floor {}: must be a finite number >= 0", args.floor)
        }
        MethodArg::Bir => Method::Bir(irad::methods::bir::BirSettings {
            vpls: args.vpls.max(2),
            frames: args.frames,
            seed: args.seed,
            strategy: match args.strategy {
                Some(StrategyArg::Standard) => irad::methods::bir::Strategy::Standard,
                Some(StrategyArg::Reverse) => irad::methods::bir::Strategy::Reverse,
                Some(StrategyArg::Both) | None => irad::methods::bir::Strategy::Both,
                Some(_) => bail!("--strategy: bir takes standard, reverse or both"),
            },
            pool: args.pool,
            light_samples: args.light_samples,
            connections: args.connections,
            depth: args.depth,
            ratio: args.ratio,
            floor: args.floor,
            power_samples: args.power_samples,
            batch: args.batch,
            light_cdf: !args.light_cdf_off,
            adaptive: !args.fixed_weights,
            clamp: ClampSettings {
                clamp: args.clamp,
                compensate: args.compensate == OnOff::On,
            },
            direct_spp: args.direct_spp.unwrap_or(irad::methods::bir::BirSettings::default().direct_spp),
            pixels,
        }),
        MethodArg::Bundles
            if !(args.roughness_m.is_finite()
                && args.roughness_m >= 0.0
                && args.contribution_clamp.is_finite()
                && args.contribution_clamp >= 0.0) =>
        {
            bail!(
                "--roughness-m {} / --contribution-clamp {}: each must be a finite number >= 0",
                args.roughness_m,
                args.contribution_clamp
            )
        }
        MethodArg::Bundles
            if args
                .env_offset
                .is_some_and(|o| !(o.is_finite() && o >= 0.0)) =>
        {
            bail!(
                "--env-offset {}: must be a finite number >= 0",
                args.env_offset.unwrap_or_default()
            )
        }
        MethodArg::Bundles => Method::Bundles(BundlesSettings {
            iterations: args.iterations,
            frames: args.frames,
            seed: args.seed,
            strategy: match args.strategy {
                Some(StrategyArg::Vpl) => BundlesStrategy::Vpl,
                Some(StrategyArg::Bundle) => BundlesStrategy::Bundle,
                Some(StrategyArg::Mis) | None => BundlesStrategy::Mis,
                Some(_) => bail!("--strategy: bundles takes vpl, bundle or mis"),
            },
            beta: match args.heuristic {
                HeuristicArg::Balance => 1.0,
                HeuristicArg::Power => 2.0,
            },
            two_bounce: args.two_bounce == OnOff::On,
            two_bounce_clamp: ClampSettings {
                clamp: args.two_bounce_clamp,
                compensate: args.compensate == OnOff::On,
            },
            suppression: match args.glossy {
                GlossyArg::None => Suppression::None,
                GlossyArg::Roughness => Suppression::Roughness {
                    m_prime: args.roughness_m,
                },
                GlossyArg::Clamp => Suppression::Contribution {
                    max: args.contribution_clamp,
                },
            },
            lights: match args.lights {
                LightsArg::All => LightSelection::All,
                LightsArg::Roulette => LightSelection::Roulette,
            },
            directions: match args.directions {
                DirectionsArg::Uniform => DirectionDensity::Uniform,
                DirectionsArg::Environment => DirectionDensity::Environment,
            },
            env_offset: args.env_offset,
            rebuild: match args.rebuild_tables {
                RebuildArg::WhenChanged => TableRebuild::WhenChanged,
                RebuildArg::EveryFrame => TableRebuild::EveryFrame,
            },
            direct_spp: args.direct_spp.unwrap_or(BundlesSettings::default().direct_spp),
            pixels,
        }),
        MethodArg::Env => Method::Env(EnvSettings {
            spp: args.spp,
            frames: args.frames,
            seed: args.seed,
            strategy: match args.strategy {
                Some(StrategyArg::Dynamic) | None => EnvStrategy::Dynamic,
                Some(StrategyArg::UniformFaces) => EnvStrategy::UniformFaces,
                Some(StrategyArg::Brdf) => EnvStrategy::Brdf,
                Some(StrategyArg::Cosine) => EnvStrategy::Cosine,
                Some(StrategyArg::Latlong) => EnvStrategy::Latlong,
                Some(StrategyArg::Hierarchical) => EnvStrategy::Hierarchical,
                Some(StrategyArg::Alpha) => EnvStrategy::Alpha,
                Some(_) => bail!(
                    "--strategy: env takes dynamic, uniform-faces, alpha, latlong, hierarchical, brdf or cosine"
                ),
            },
            face_resolution: args.face_resolution,
            light_only: args.light_only,
            integer_counts: args.integer_counts,
            alpha_samples: args.alpha_samples,
            shadows: !args.no_shadows,
            shared_samples: args.shared_samples,
            rebuild: match args.rebuild_tables {
                RebuildArg::WhenChanged => TableRebuild::WhenChanged,
                RebuildArg::EveryFrame => TableRebuild::EveryFrame,
            },
            pixels,
        }),
        MethodArg::Lightfield => Method::Lightfield(LightfieldSettings {
            spp: args.spp,
            frames: args.frames,
            k_max: args.k_max,
            strategy: match args.strategy {
                Some(StrategyArg::Restricted) | None => LightfieldStrategy::Restricted,
                Some(StrategyArg::Uniform) => LightfieldStrategy::Uniform,
                Some(StrategyArg::Precomputed) => LightfieldStrategy::Precomputed,
                Some(StrategyArg::BruteForce) => LightfieldStrategy::BruteForce,
                Some(_) => bail!(
                    "--strategy: lightfield takes restricted, uniform, precomputed or brute-force"
                ),
            },
            secant: !args.binary_search,
            shared_samples: args.shared_samples,
            averaged_visibility: args.averaged_visibility,
            shadows: !args.no_shadows,
            sampling_only: false,
            seed: args.seed,
            rebuild: match args.rebuild_tables {
                RebuildArg::WhenChanged => TableRebuild::WhenChanged,
                RebuildArg::EveryFrame => TableRebuild::EveryFrame,
            },
            pixels,
        }),
    };
    let out = args
        .out
        .unwrap_or_else(|| PathBuf::from("out").join(&scene.name));
    let job = RenderJob {
        scene: &scene,
        method,
        out,
        exposure: args.exposure,
        reference: args.reference,
    };
    let cam = &scene.camera;
    println!(
        "rendering {} ({}x{}, {} triangles) with {} on {}",
        render::scene_label(&scene),
        cam.width,
        cam.height,
        scene.triangles.len(),
        job.method.name(),
        device_line(ctx.info())
    );
    let bar = progress(job.method_samples(), "render");
    let report = render::render(&ctx, &job, |done, _| bar.set_position(done as u64))?;
    bar.finish_and_clear();
    let r = &report.record;
    println!("per-pass GPU time:\n{}", report.passes);
    if let Some(gpu_ms) = r.gpu_ms_total {
        let paths = r.samples as f64 * cam.width as f64 * cam.height as f64;
        println!(
            "{} samples per pixel in {:.3} s GPU ({:.3} s wall): {:.2} M samples/s",
            r.samples,
            gpu_ms / 1e3,
            r.wall_ms / 1e3,
            paths / gpu_ms / 1e3
        );
    }
    if let Some(m) = &r.metrics {
        println!(
            "against the reference: relMSE {:.4e}, RMSE {:.4e}, Lab error {:.3}, bias {:.3}%, outliers {:.4}%, NaN/Inf {}",
            m.rel_mse,
            m.rmse,
            m.lab_error,
            100.0 * m.bias,
            100.0 * m.outliers,
            m.nan_inf
        );
    }
    for w in &r.warnings {
        eprintln!("warning: {w}");
    }
    let (exr, png, json) = &report.paths;
    println!(
        "wrote {}, {} and {}",
        exr.display(),
        png.display(),
        json.display()
    );
    Ok(())
}

fn bench_suite(options: &ContextOptions, args: SuiteArgs) -> Result<()> {
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
            let _writing = suite::output::WRITING.lock();
            std::process::exit(130);
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
    let results =
        suite::run(&ctx, &suite, &options, |event| match event {
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
                // Only rendered runs teach the estimate, from their first render on (a
                // scene's reference comes before it).
                if let (Status::Ok, Some(start)) = (record.status, run_start.take()) {
                    eta.finished(&suite, plan[run - 1], start.elapsed().as_secs_f64());
                }
                run_start = None;
                if let Some(left) = eta.left(&suite, &plan[run..]) {
                    overall.set_message(format!(", about {} left", indicatif::HumanDuration(left)));
                }
                let line =
                    match record.status {
                        Status::Ok => {
                            let m = record.metrics.expect("ok runs are scored");
                            format!(
                        "{:<48} GPU {:>9} ms  relMSE {:.3e}  bias {:>6.2}%  outliers {:.3}%{}",
                        record.id,
                        record.gpu_ms.map(|t| format!("{t:.2}")).unwrap_or("-".into()),
                        m.rel_mse,
                        100.0 * m.bias,
                        100.0 * m.outliers,
                        if record.pareto { "  *" } else { "" }
                    )
                        }
                        s => format!("{:<48} {}: {}", record.id, s.as_str(), record.note),
                    };
                bars.suspend(|| println!("{line}"));
            }
        })?;
    overall.finish_and_clear();
    current.finish_and_clear();
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
            "interrupted: {} of {} runs recorded; the outputs hold them, marked incomplete",
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

fn progress(len: u64, what: &str) -> ProgressBar {
    let bar = ProgressBar::new(len);
    bar.set_style(
        ProgressStyle::with_template(&format!(
            "{what} [{{bar:30}}] {{pos}}/{{len}} ({{elapsed}} elapsed, {{eta}} left) {{msg}}"
        ))
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
    if ContextOptions::force_staging_from_env() {
        println!(
            "staging: forced (IRAD_FORCE_STAGING): every buffer device-local only, written and \
             read through staging buffers, as on a discrete GPU"
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

/// `--strategies` of a bench: each name one of `all`'s, or an error listing them.
fn strategies_by_name<S: Copy>(
    names: &[String],
    all: &[S],
    name: impl Fn(S) -> &'static str,
    method: &str,
) -> Result<Vec<S>> {
    names
        .iter()
        .map(|wanted| {
            all.iter()
                .copied()
                .find(|&s| name(s) == wanted)
                .ok_or_else(|| {
                    let names: Vec<&str> = all.iter().map(|&s| name(s)).collect();
                    anyhow::anyhow!(
                        "--strategies: no {method} strategy {wanted:?} (one of {})",
                        names.join(", ")
                    )
                })
        })
        .collect()
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
    options.check(available_memory(), |w| eprintln!("warning: {w}"))?;
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
