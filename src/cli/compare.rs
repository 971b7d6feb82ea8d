//! `irad compare A B`: an image (or a folder of frames) scored against a reference, with the
//! figures every report uses (docs/DESIGN.md "Error metrics") and full-size error maps.

use std::fs;
use std::path::{Path, PathBuf};

use anyhow::{bail, Context as _, Result};
use serde::Serialize;

use irad::html::viewer::{FlipMap, ViewerData};
use irad::image::error_maps::{self, Rgb8};
use irad::image::flip::{self, DEFAULT_PIXELS_PER_DEGREE};
use irad::image::metrics::{self, Metrics, SequenceMetrics, SequenceScore};
use irad::image::{exr, png, Image};

#[derive(clap::Args)]
pub struct CompareArgs {
    /// The image under test: an EXR, or a folder of frames (frame_NNNN.exr, as `irad render
    /// --sequence` writes them).
    test: PathBuf,
    /// The reference: an EXR of the same size, or a folder holding the same frames.
    reference: PathBuf,
    /// Output stem. For two EXRs: OUT.json (the figures), OUT.png (per-pixel relMSE, log scale),
    /// OUT_signed.png (signed relative error of luminance: blue darker, red brighter) and
    /// OUT_flip.png (HDR-FLIP), each with its colour bar. For two folders: the folder OUT with
    /// compare.json and those three maps per frame (frame_NNNN.png, _signed.png, _flip.png).
    /// Without it nothing is written.
    #[arg(short, long, value_name = "OUT")]
    out: Option<PathBuf>,
    /// Leave HDR-FLIP out (it costs about a second per megapixel on this CPU).
    #[arg(long)]
    no_flip: bool,
    /// Also write the interactive viewer (docs/commands.md "Looking at images"): OUT.html for
    /// two EXRs, OUT/compare.html for two folders (a player over the frames with their error
    /// plot). One self-contained page; it opens from file:// with no network.
    #[arg(long, requires = "out")]
    html: bool,
}

/// What compare.json (or OUT.json) holds.
#[derive(Serialize)]
struct Record {
    test: String,
    reference: String,
    /// One image: its figures.
    #[serde(skip_serializing_if = "Option::is_none")]
    metrics: Option<Metrics>,
    /// Folders: each frame's figures, by frame number...
    #[serde(skip_serializing_if = "Vec::is_empty")]
    frames: Vec<FrameRecord>,
    /// ...and the sequence's (mean, worst frame, flicker).
    #[serde(skip_serializing_if = "Option::is_none")]
    sequence: Option<SequenceMetrics>,
}

#[derive(Serialize)]
struct FrameRecord {
    frame: u32,
    metrics: Metrics,
}

pub fn run(args: CompareArgs) -> Result<()> {
    let (test_dir, reference_dir) = (args.test.is_dir(), args.reference.is_dir());
    if test_dir != reference_dir {
        bail!(
            "{} is {} but {} is {}: compare two EXRs or two folders of frames",
            args.test.display(),
            kind(test_dir),
            args.reference.display(),
            kind(reference_dir)
        );
    }
    let record = if test_dir {
        compare_folders(&args)?
    } else {
        compare_images(&args)?
    };
    if let Some(out) = &args.out {
        let json = match test_dir {
            true => out.join("compare.json"),
            false => with_suffix(out, ".json"),
        };
        let text = serde_json::to_string_pretty(&record)? + "\n";
        fs::write(&json, text).with_context(|| format!("writing {}", json.display()))?;
        println!("wrote {}", json.display());
    }
    Ok(())
}

fn kind(dir: bool) -> &'static str {
    match dir {
        true => "a folder",
        false => "not one",
    }
}

fn read(path: &Path) -> Result<Image> {
    exr::read(path).with_context(|| format!("reading {}", path.display()))
}

/// `stem` with `suffix` added to its file name (`out/a` + `_flip.png`: `out/a_flip.png`).
fn with_suffix(stem: &Path, suffix: &str) -> PathBuf {
    let mut name = stem.as_os_str().to_owned();
    name.push(suffix);
    PathBuf::from(name)
}

/// The figures of `x` against `r` (FLIP unless left out) and its per-pixel map.
fn score(x: &Image, r: &Image, with_flip: bool) -> Result<(Metrics, Option<flip::FlipResult>)> {
    let mut m = metrics::compare(x, r)?;
    let mut map = None;
    if with_flip {
        match flip::hdr_flip(r, x, DEFAULT_PIXELS_PER_DEGREE) {
            Ok(f) => {
                m.flip = Some(f.mean);
                map = Some(f);
            }
            // A non-finite test image has no FLIP; its NaN/Inf count says why.
            Err(metrics::MetricsError::NonFiniteTest { .. }) => {}
            Err(e) => return Err(e.into()),
        }
    }
    Ok((m, map))
}

fn line(m: &Metrics) -> String {
    let flip = m.flip.map(|f| format!("  FLIP {f:.4}")).unwrap_or_default();
    format!(
        "relMSE {:.4e}  RMSE {:.4e}  bias {:.2}%  outliers {:.3}%  Lab error {:.3}  NaN/Inf {}{flip}",
        m.rel_mse,
        m.rmse,
        100.0 * m.bias,
        100.0 * m.outliers,
        m.lab_error,
        m.nan_inf
    )
}

/// The three maps of `x` against `r` at `stem`.png, `stem`_signed.png and `stem`_flip.png.
fn write_maps(stem: &Path, x: &Image, r: &Image, flip: Option<&flip::FlipResult>) -> Result<()> {
    let mut maps: Vec<(String, Rgb8)> = vec![
        (".png".into(), error_maps::rel_mse_map(x, r)),
        ("_signed.png".into(), error_maps::signed_map(x, r)),
    ];
    if let Some(f) = flip {
        maps.push(("_flip.png".into(), error_maps::flip_map(f)));
    }
    for (suffix, map) in maps {
        let path = with_suffix(stem, &suffix);
        png::write_rgb8(&path, map.width, map.height, &map.data)?;
        println!("wrote {}", path.display());
    }
    Ok(())
}

fn flip_map(f: flip::FlipResult) -> FlipMap {
    FlipMap {
        width: f.width,
        height: f.height,
        values: f.error_map,
    }
}

/// The viewer of the test against the reference, for `frames` frames of `size`: the two
/// named by their files (or "test ..." and "reference ..." where the names are the same), at
/// the frame rate of the test folder's sequence.json where there is one.
fn viewer(args: &CompareArgs, frames: usize, size: (u32, u32)) -> Result<ViewerData> {
    let name = |p: &Path| {
        p.file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_else(|| p.display().to_string())
    };
    let (mut a, mut b) = (name(&args.test), name(&args.reference));
    if a == b {
        (a, b) = (format!("test {a}"), format!("reference {b}"));
    }
    let fps = fs::read_to_string(args.test.join("sequence.json"))
        .ok()
        .and_then(|t| serde_json::from_str::<serde_json::Value>(&t).ok())
        .and_then(|v| v["fps"].as_f64())
        .unwrap_or(10.0) as f32;
    // FLIP maps are the ones compare computes (none under --no-flip), not a second time; the
    // page's size is reckoned with them.
    ViewerData::new(vec![a, b], Some(1), fps, frames, size, !args.no_flip)
}

/// The viewer page at `path`, under the figures' line.
fn write_page(args: &CompareArgs, path: &Path, data: &ViewerData, figures: &str) -> Result<()> {
    let intro = format!(
        "<p>{} against the reference {}</p><pre>{}</pre>",
        irad::html::escape(&irad::image::sidecar::absolute(&args.test)),
        irad::html::escape(&irad::image::sidecar::absolute(&args.reference)),
        irad::html::escape(figures)
    );
    let html = irad::html::viewer::page("irad compare", &intro, data);
    fs::write(path, html).with_context(|| format!("writing {}", path.display()))?;
    println!("wrote {}", path.display());
    Ok(())
}

fn compare_images(args: &CompareArgs) -> Result<Record> {
    let (x, r) = (read(&args.test)?, read(&args.reference)?);
    let (m, flip) = score(&x, &r, !args.no_flip).with_context(|| {
        format!(
            "comparing {} against {}",
            args.test.display(),
            args.reference.display()
        )
    })?;
    println!("{}", line(&m));
    if let Some(out) = &args.out {
        if let Some(parent) = out.parent().filter(|p| !p.as_os_str().is_empty()) {
            fs::create_dir_all(parent).with_context(|| format!("creating {}", parent.display()))?;
        }
        write_maps(out, &x, &r, flip.as_ref())?;
        if args.html {
            let mut data = viewer(args, 1, (x.width, x.height))?;
            data.push_with_flips(0, vec![x, r], vec![flip.map(flip_map), None])?;
            write_page(args, &with_suffix(out, ".html"), &data, &line(&m))?;
        }
    }
    Ok(Record {
        test: irad::image::sidecar::absolute(&args.test),
        reference: irad::image::sidecar::absolute(&args.reference),
        metrics: Some(m),
        frames: Vec::new(),
        sequence: None,
    })
}

/// The frames frame_NNNN.exr in `dir`, by number.
fn frames(dir: &Path) -> Result<Vec<(u32, PathBuf)>> {
    let mut found = Vec::new();
    for entry in fs::read_dir(dir).with_context(|| format!("reading {}", dir.display()))? {
        let path = entry?.path();
        let name = path
            .file_name()
            .and_then(|n| n.to_str())
            .unwrap_or_default();
        let number = name
            .strip_prefix("frame_")
            .and_then(|n| n.strip_suffix(".exr"))
            .filter(|n| !n.is_empty() && n.bytes().all(|b| b.is_ascii_digit()))
            .and_then(|n| n.parse::<u32>().ok());
        if let Some(n) = number {
            found.push((n, path));
        }
    }
    found.sort();
    if let Some(w) = found.windows(2).find(|w| w[0].0 == w[1].0) {
        bail!(
            "{} and {} are both frame {}",
            w[0].1.display(),
            w[1].1.display(),
            w[0].0
        );
    }
    Ok(found)
}

fn compare_folders(args: &CompareArgs) -> Result<Record> {
    let (tests, references) = (frames(&args.test)?, frames(&args.reference)?);
    if tests.is_empty() {
        bail!(
            "{} holds no frames (frame_NNNN.exr, as `irad render --sequence` writes)",
            args.test.display()
        );
    }
    let missing: Vec<String> = tests
        .iter()
        .filter(|(n, _)| !references.iter().any(|(m, _)| m == n))
        .map(|(n, _)| format!("frame_{n:04}.exr"))
        .collect();
    if !missing.is_empty() {
        bail!(
            "{} lacks {} of the frames of {}: {}",
            args.reference.display(),
            missing.len(),
            args.test.display(),
            missing.join(", ")
        );
    }
    if let Some(out) = &args.out {
        fs::create_dir_all(out).with_context(|| format!("creating {}", out.display()))?;
    }
    // The test folder may hold part of the reference's frames (`--sequence=A..B`); a gap in
    // its frames breaks the flicker, taken only between frames that follow each other.
    let skipped = references.len() - tests.len();
    if skipped > 0 {
        println!(
            "{} of the reference's frames are not in {}: scoring the {} that are",
            skipped,
            args.test.display(),
            tests.len()
        );
    }
    let mut sequence = SequenceScore::default();
    let mut records = Vec::new();
    // The viewer's frames, where --html asks for them.
    let mut page: Option<ViewerData> = None;
    let mut previous: Option<u32> = None;
    for (n, path) in &tests {
        if previous.is_some_and(|p| p + 1 != *n) {
            sequence.gap();
        }
        previous = Some(*n);
        let reference = &references.iter().find(|(m, _)| m == n).expect("checked").1;
        let (x, r) = (read(path)?, read(reference)?);
        let (mut m, flip) = score(&x, &r, !args.no_flip)
            .with_context(|| format!("comparing frame {n}: {}", path.display()))?;
        if let Some(out) = &args.out {
            write_maps(&out.join(format!("frame_{n:04}")), &x, &r, flip.as_ref())?;
        }
        let flip_mean = m.flip;
        if args.html {
            if page.is_none() {
                page = Some(viewer(args, tests.len(), (x.width, x.height))?);
            }
            let flips = vec![flip.map(flip_map), None];
            page.as_mut()
                .expect("made")
                .push_with_flips(*n, vec![x.clone(), r.clone()], flips)?;
        }
        m = sequence.push(x, r)?;
        m.flip = flip_mean;
        println!("frame {n:4}  {}", line(&m));
        records.push(FrameRecord {
            frame: *n,
            metrics: m,
        });
    }
    let (_, mut summary) = sequence.finish();
    // The mean's FLIP over the frames that have one (SequenceScore scores without FLIP).
    let flips: Vec<f64> = records.iter().filter_map(|f| f.metrics.flip).collect();
    if !flips.is_empty() {
        summary.mean.flip = Some(flips.iter().sum::<f64>() / flips.len() as f64);
    }
    let worst = records[summary.worst_frame].frame;
    let figures = format!(
        "{} frames: mean {}\nworst frame {worst} (relMSE {:.4e}), flicker {:.4}",
        records.len(),
        line(&summary.mean),
        summary.worst_rel_mse,
        summary.flicker
    );
    println!("{figures}");
    if let (Some(data), Some(out)) = (&page, &args.out) {
        write_page(args, &out.join("compare.html"), data, &figures)?;
    }
    Ok(Record {
        test: irad::image::sidecar::absolute(&args.test),
        reference: irad::image::sidecar::absolute(&args.reference),
        metrics: None,
        frames: records,
        sequence: Some(summary),
    })
}
