//! `irad render`: one scene, one method, its image, record and summary.

use std::path::{Path, PathBuf};

use anyhow::{bail, Context as _, Result};
use clap::builder::{PossibleValue, PossibleValuesParser};

use irad::gpu::{Context, ContextOptions};
use irad::html::viewer::ViewerData;
use irad::render::{self, RenderJob};
use irad::scene;

use super::method_flags::{self, MethodFlags};
use super::{device_line, progress};

#[derive(clap::Args)]
pub struct RenderArgs {
    /// Scene file: TOML, Mitsuba .xml or glTF .gltf/.glb (formats: docs/scenes.md); default: the
    /// embedded Cornell box.
    scene: Option<PathBuf>,
    /// Rendering method (`irad methods` lists them and their settings).
    #[arg(long, default_value = "reference", value_parser = method_names())]
    method: String,
    /// Output stem: writes OUT.exr, OUT.png and OUT.json [default: out/<scene name>]. A
    /// folder (an existing one, or OUT ending in `/`, `.` or `..`) gets OUT/render.exr, .png and
    /// .json. The files are checked writable before rendering and replace an earlier render's
    /// together, the JSON last.
    #[arg(short, long, value_name = "OUT")]
    out: Option<PathBuf>,
    /// Exposure of the PNG in stops (the EXR is never tone mapped).
    #[arg(long, default_value_t = 0.0, allow_negative_numbers = true)]
    exposure: f32,
    /// Render at WIDTHxHEIGHT instead of the scene's `camera.resolution` (each in 1..=16384).
    /// The vertical field of view is kept, so another aspect ratio shows more or less of the
    /// scene's sides.
    #[arg(long, value_name = "WxH", value_parser = super::parse_size)]
    resolution: Option<(u32, u32)>,
    /// Reference EXR of the same scene and size: adds relMSE, RMSE, Lab error, bias and
    /// outliers against it to the JSON and the summary. With --sequence, a folder of the same
    /// animation's reference frames (an earlier --sequence): each frame is scored against its
    /// own, and sequence.json gets the mean, the worst frame and the flicker.
    #[arg(long, value_name = "EXR")]
    reference: Option<PathBuf>,
    /// The frame of an animated scene ([animation] in its file) to render as a still [default:
    /// 0]. It renders with seed SEED + N, as frame N of `--sequence` does, so the two agree bit
    /// for bit.
    #[arg(long, value_name = "N")]
    frame: Option<u32>,
    /// A glTF scene's camera: `cameras[N]` of the file (0-based) [default: the lowest-numbered
    /// camera a node places].
    #[arg(long, value_name = "N")]
    camera: Option<usize>,
    /// Render an animated scene frame by frame, each frame its own image from the method's
    /// count (`--samples-per-frame`), into the folder OUT: frame_NNNN.exr, .png and .json,
    /// sequence.json (each frame's GPU time per pass, seed and files; device and settings once)
    /// and preview.png (an animated PNG; preview.mp4 too where ffmpeg is installed). All frames,
    /// or `--sequence=A..B` for frames A to B-1. An interrupted sequence resumes from the
    /// frames it completed. (`--frames` is the methods' own count of samples, so the range is
    /// the value of --sequence.)
    #[arg(long, value_name = "A..B", num_args = 0..=1, require_equals = true, default_missing_value = "")]
    sequence: Option<String>,
    /// With --sequence: the method's count per frame (samples per pixel for the path tracer,
    /// frames for the others) [default: the method's own count setting].
    #[arg(long, value_name = "K", requires = "sequence")]
    samples_per_frame: Option<u32>,
    /// With --sequence and --reference: leave HDR-FLIP out of the per-frame scores (it costs
    /// about 40 ms a frame at 128x96, growing with the pixel count and, on a mostly black
    /// reference, up to 5 times that).
    #[arg(long, requires = "reference", requires = "sequence")]
    no_flip: bool,
    /// Also write the interactive viewer (docs/commands.md "Looking at images"): OUT.html
    /// beside OUT.exr, the render against --reference where given (split, flip, error maps,
    /// HDR-FLIP); with --sequence OUT/sequence.html, a player over the frames with their error
    /// plot against the reference frames. One self-contained page; it opens from file://.
    #[arg(long)]
    html: bool,
    #[command(flatten)]
    settings: MethodFlags,
}

/// `--method`'s values, each with what it is.
fn method_names() -> PossibleValuesParser {
    PossibleValuesParser::new(
        irad::methods::Registry::builtin()
            .entries()
            .iter()
            .map(|e| PossibleValue::new(e.name()).help(e.summary())),
    )
}

impl RenderArgs {
    /// `--method` with its settings' flags.
    pub fn method(&self) -> Result<irad::methods::Method> {
        self.settings.method(&self.method)
    }
}

/// Renders, writes and prints the summary.
pub fn run(options: &ContextOptions, args: RenderArgs) -> Result<()> {
    let method = args.method()?;
    let camera = args.camera;
    let scene = match &args.scene {
        Some(path) => {
            // `--two-bounce off`: a switch's value goes after `=`, so clap took it as SCENE.
            let text = path.to_string_lossy();
            let args: Vec<String> = std::env::args().collect();
            if let Some(flag) = method_flags::switch_before(&args, &text) {
                bail!(
                    "scene `{text}` not found: {flag} is a switch and takes its value after `=` ({})",
                    method_flags::switch_written(&flag, &text)
                );
            }
            super::load_scene(path, camera)?
        }
        None if camera.is_some() => bail!("--camera picks a glTF scene's camera: give one"),
        None => scene::default_scene(),
    };
    let scene = match args.resolution {
        Some((width, height)) => {
            let mut scene = scene;
            scene.camera.width = width;
            scene.camera.height = height;
            scene
        }
        None => scene,
    };
    if let Some(range) = &args.sequence {
        if args.frame.is_some() {
            bail!("--sequence renders every frame: --frame is for one render");
        }
        let method = match args.samples_per_frame {
            Some(k) => {
                let flag = format!("--{}", method.count_key().replace('_', "-"));
                let given =
                    std::env::args().any(|a| a == flag || a.starts_with(&format!("{flag}=")));
                if given {
                    bail!(
                        "--samples-per-frame {k} and {flag} both set {}'s count a frame: give one",
                        method.name()
                    );
                }
                // Through the settings table, so the count's range is checked as {flag}'s is.
                let mut values = method.parameters();
                values.insert(method.count_key().to_string(), k.into());
                values.insert("seed".into(), method.seed().into());
                let table: toml::Table = toml::from_str(&toml::to_string(&values)?)?;
                irad::methods::Registry::builtin()
                    .from_params(method.name(), &table)
                    .map_err(|e| anyhow::anyhow!("--samples-per-frame {k}: {e}"))?
            }
            None => method,
        };
        return super::sequence::run(
            options,
            &scene,
            method,
            range,
            args.out,
            args.exposure,
            args.reference,
            !args.no_flip,
            args.html,
        );
    }
    let (scene, frame) = match (&scene.animation, args.frame) {
        (Some(animation), frame) => {
            let f = frame.unwrap_or(0);
            if f >= animation.frames {
                bail!(
                    "--frame {f}: the animation has frames 0..{} ({} frames)",
                    animation.frames,
                    animation.frames
                );
            }
            println!(
                "animation frame {f} of 0..{} as a still (--frame N picks another; --sequence \
                 renders them all)",
                animation.frames
            );
            (scene.at_frame(f)?, Some(f))
        }
        (None, Some(f)) => bail!(
            "--frame {f}: {} is not animated (no [animation] in its file)",
            render::scene_label(&scene)
        ),
        (None, None) => (scene, None),
    };
    let method = match frame {
        Some(f) => irad::sequence::frame_method(&method, f),
        None => method,
    };
    let out = args
        .out
        .unwrap_or_else(|| PathBuf::from("out").join(&scene.name));
    let reference = args.reference.clone();
    let job = RenderJob {
        scene: &scene,
        method,
        out,
        exposure: args.exposure,
        reference: args.reference,
        frame,
    };
    // Before the device opens: a bad exposure, folder or reference costs nothing.
    let checked = job.check()?;
    let ctx = Context::new(options)?;
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
    // Within a long frame (or submission of frames), how far its dispatches have come.
    let within = bar.clone();
    irad::methods::progressive::observe_frames(Some(Box::new(move |w| {
        let frames = match w.frames {
            1 => format!("frame {}", w.frames_done + 1),
            n => format!("frames {}-{}", w.frames_done + 1, w.frames_done + n),
        };
        within.set_message(format!(
            "{frames}: {} of ~{} dispatches",
            w.dispatches_done, w.dispatches
        ));
    })));
    let report = render::render_checked(&ctx, &job, checked, |done, _| {
        within_done(&bar, done);
    });
    irad::methods::progressive::observe_frames(None);
    let report = report?;
    bar.finish_and_clear();
    let r = &report.record;
    println!("per-pass GPU time:\n{}", report.passes);
    if let Some(l) = &r.load {
        println!(
            "scene to the device: {:.0} ms parsing, {:.0} ms building the BVH, {:.0} ms the light \
             BVH, {:.0} ms the whole upload",
            l.parse_ms, l.triangle_bvh_ms, l.light_bvh_ms, l.upload_ms
        );
    }
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
    let files: Vec<String> = report
        .files
        .all()
        .iter()
        .map(|p| p.display().to_string())
        .collect();
    let (json, images) = files.split_last().expect("a render writes files");
    println!("wrote {} and {json}", images.join(", "));
    if args.html {
        let path = report.files.exr.with_extension("html");
        let mut images = vec![("render".to_string(), report.image)];
        if let Some(r) = &reference {
            images.push(("reference".into(), irad::image::exr::read(r)?));
        }
        let with_reference = reference.is_some().then_some(1);
        let data = ViewerData::still(images, with_reference, true)?;
        let intro = format!(
            "<p>{} with {}{}</p>",
            irad::html::escape(&render::scene_label(&scene)),
            irad::html::escape(&r.method),
            match &reference {
                Some(p) => format!(
                    ", against {}",
                    irad::html::escape(&irad::image::sidecar::absolute(p))
                ),
                None => String::new(),
            }
        );
        write_page(&path, "irad render", &intro, &data)?;
    }
    Ok(())
}

/// Writes a viewer page and says so.
pub fn write_page(path: &Path, title: &str, intro: &str, data: &ViewerData) -> Result<()> {
    let html = irad::html::viewer::page(title, intro, data);
    std::fs::write(path, html).with_context(|| format!("writing {}", path.display()))?;
    println!("wrote {}", path.display());
    Ok(())
}

/// Frames `done`: the bar's position, and no message of a submission under way.
fn within_done(bar: &indicatif::ProgressBar, done: u32) {
    bar.set_position(done as u64);
    bar.set_message("");
}
