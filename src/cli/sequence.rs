//! `irad render --sequence`: an animated scene frame by frame into a folder
//! (irad::sequence::render_sequence), with a bar counting frames.

use std::ops::Range;
use std::path::PathBuf;

use anyhow::{bail, Context as _, Result};

use irad::gpu::{Context, ContextOptions};
use irad::html::viewer::ViewerData;
use irad::image::exr;
use irad::methods::Method;
use irad::render;
use irad::scene::Scene;
use irad::sequence::{self, SequenceJob};

use super::{device_line, progress};

/// `A..B` (frames A to B-1), `A..=B`, or empty for all of `frames`.
fn parse_range(text: &str, frames: u32) -> Result<Range<u32>> {
    if text.is_empty() {
        return Ok(0..frames);
    }
    let bad = || {
        anyhow::anyhow!(
            "--sequence={text}: give frames as A..B (A to B-1) or A..=B, within the animation's \
             0..{frames}"
        )
    };
    let (a, b, inclusive) = match text.split_once("..=") {
        Some((a, b)) => (a, b, true),
        None => {
            let (a, b) = text.split_once("..").ok_or_else(bad)?;
            (a, b, false)
        }
    };
    let a: u32 = a.trim().parse().map_err(|_| bad())?;
    let b: u32 = b.trim().parse().map_err(|_| bad())?;
    let end = if inclusive {
        b.checked_add(1).ok_or_else(bad)?
    } else {
        b
    };
    if a >= end || end > frames {
        return Err(bad());
    }
    Ok(a..end)
}

#[allow(clippy::too_many_arguments)]
pub fn run(
    options: &ContextOptions,
    scene: &Scene,
    method: Method,
    range: &str,
    out: Option<PathBuf>,
    exposure: f32,
    reference: Option<PathBuf>,
    flip: bool,
    html: bool,
) -> Result<()> {
    let Some(animation) = &scene.animation else {
        bail!(
            "--sequence: {} is not animated (no [animation] in its file; docs/animation.md)",
            render::scene_label(scene)
        );
    };
    let frames = parse_range(range, animation.frames)?;
    let out = out
        .unwrap_or_else(|| PathBuf::from("out").join(format!("{}-{}", scene.name, method.name())));
    let ctx = Context::new(options)?;
    let cam = &scene.camera;
    println!(
        "rendering frames {}..{} of {} ({}x{}, {} fps, {} triangles) with {}, {} {} a frame, \
         into {} on {}",
        frames.start,
        frames.end,
        render::scene_label(scene),
        cam.width,
        cam.height,
        animation.fps,
        scene.triangles.len(),
        method.name(),
        method.samples(),
        method.count_key(),
        out.display(),
        device_line(ctx.info())
    );
    let bar = progress(frames.len() as u64, "frames");
    let count_key = method.count_key();
    let job = SequenceJob {
        scene,
        method,
        frames,
        out,
        exposure,
        reference,
        flip,
    };
    let report = sequence::render_sequence(
        &ctx,
        &job,
        |p| {
            bar.set_position(p.frames_done as u64);
            match p.frames_done < p.frames {
                true => bar.set_message(format!(
                    "frame {}: {}/{} {}",
                    p.frame, p.samples_done, p.samples, count_key
                )),
                false => bar.set_message("previews"),
            }
        },
        |_, _| {},
    );
    bar.finish_and_clear();
    let report = report?;
    for w in &report.warnings {
        log::warn!("{w}");
    }
    if !report.resumed.is_empty() {
        println!(
            "kept {} frame(s) complete from an earlier run ({}..={})",
            report.resumed.len(),
            report.resumed[0],
            report.resumed[report.resumed.len() - 1]
        );
    }
    let gpu: Vec<f64> = report
        .record
        .rendered
        .iter()
        .filter_map(|f| f.gpu_ms_total)
        .collect();
    if !gpu.is_empty() {
        let mean = gpu.iter().sum::<f64>() / gpu.len() as f64;
        let worst = gpu.iter().cloned().fold(0.0, f64::max);
        println!("GPU time a frame: mean {mean:.1} ms, longest {worst:.1} ms");
    }
    if let Some(m) = &report.record.metrics {
        println!(
            "against the reference frames: relMSE mean {:.4e}, worst {:.4e} (frame {}), bias mean \
             {:.3}%, flicker {:.4e}",
            m.mean.rel_mse,
            m.worst_rel_mse,
            m.worst_frame,
            100.0 * m.mean.bias,
            m.flicker
        );
        if let Some(flip) = m.mean.flip {
            println!("HDR-FLIP mean over frames {flip:.4}");
        }
    }
    let previews: Vec<String> = report
        .previews
        .iter()
        .map(|p| p.display().to_string())
        .collect();
    println!(
        "wrote {} frames, sequence.json and {} in {}",
        report.record.rendered.len(),
        previews.join(", "),
        job.out.display()
    );
    if html {
        write_page(&job, &report.record, flip)?;
    }
    Ok(())
}

/// OUT/sequence.html: the frames of this run's range (and the reference's) in the viewer's
/// player, each box-filtered as it is read.
fn write_page(job: &SequenceJob, record: &sequence::SequenceRecord, flip: bool) -> Result<()> {
    let mut names = vec!["render".to_string()];
    if job.reference.is_some() {
        names.push("reference".into());
    }
    // The folder may hold frames of an earlier run outside this range: they are not shown.
    let frames: Vec<u32> = record
        .rendered
        .iter()
        .map(|f| f.frame)
        .filter(|f| job.frames.contains(f))
        .collect();
    let read =
        |path: PathBuf| exr::read(&path).with_context(|| format!("reading {}", path.display()));
    let size = (job.scene.camera.width, job.scene.camera.height);
    let mut data = ViewerData::new(
        names,
        job.reference.as_ref().map(|_| 1),
        record.fps,
        frames.len(),
        size,
        flip && job.reference.is_some(),
    )?;
    for &f in &frames {
        let mut images = vec![read(
            sequence::frame_stem(&job.out, f).with_extension("exr"),
        )?];
        if let Some(dir) = &job.reference {
            images.push(read(sequence::frame_stem(dir, f).with_extension("exr"))?);
        }
        data.push(f, images)?;
    }
    let intro = format!(
        "<p>{} with {}, frames {}..{}{}</p>",
        irad::html::escape(&record.scene),
        irad::html::escape(&record.method),
        record.frames[0],
        record.frames[1],
        match &job.reference {
            Some(p) => format!(
                ", against the frames in {}",
                irad::html::escape(&irad::image::sidecar::absolute(p))
            ),
            None => String::new(),
        }
    );
    super::render::write_page(
        &job.out.join("sequence.html"),
        "irad render --sequence",
        &intro,
        &data,
    )
}

#[cfg(test)]
mod tests {
    use super::parse_range;

    #[test]
    fn ranges_are_read_as_rust_writes_them() {
        assert_eq!(parse_range("", 10).unwrap(), 0..10);
        assert_eq!(parse_range("2..5", 10).unwrap(), 2..5);
        assert_eq!(parse_range("2..=5", 10).unwrap(), 2..6);
        for bad in ["5..2", "0..11", "x..3", "3", "4..4", "0..=10"] {
            assert!(parse_range(bad, 10).is_err(), "{bad}");
        }
    }
}
