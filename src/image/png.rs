//! PNG out through the `png` crate: 8-bit sRGB RGB after the tone map of `tonemap.rs`, with an
//! sRGB chunk so viewers do not re-interpret the gamma.

use std::fs::File;
use std::io::BufWriter;
use std::path::Path;

use anyhow::{ensure, Context, Result};

use super::{tonemap, Image};

/// Writes `image` tone-mapped at `exposure` stops (0 for none) as an 8-bit sRGB RGB PNG.
pub fn write(path: &Path, image: &Image, exposure: f32) -> Result<()> {
    ensure!(
        exposure.is_finite(),
        "writing {}: exposure must be a finite number of stops, got {exposure}",
        path.display()
    );
    ensure!(
        image.width > 0 && image.height > 0,
        "writing {}: cannot write a {}x{} image",
        path.display(),
        image.width,
        image.height
    );
    ensure!(
        image.pixels.len() == image.width as usize * image.height as usize,
        "writing {}: a {}x{} image holds {} pixels, not {}",
        path.display(),
        image.width,
        image.height,
        image.width as usize * image.height as usize,
        image.pixels.len()
    );
    write_rgb8(
        path,
        image.width,
        image.height,
        &tonemap::tonemap_rgb8(image, exposure),
    )
}

/// Writes 8-bit sRGB RGB `data` (row 0 at the top, 3 bytes per pixel) as a PNG.
pub fn write_rgb8(path: &Path, width: u32, height: u32, data: &[u8]) -> Result<()> {
    ensure!(
        data.len() == 3 * width as usize * height as usize && width > 0 && height > 0,
        "writing {}: {} bytes are not a {width}x{height} RGB image",
        path.display(),
        data.len()
    );
    let file = File::create(path).with_context(|| format!("creating {}", path.display()))?;
    let mut encoder = ::png::Encoder::new(BufWriter::new(file), width, height);
    encoder.set_color(::png::ColorType::Rgb);
    encoder.set_depth(::png::BitDepth::Eight);
    encoder.set_source_srgb(::png::SrgbRenderingIntent::Perceptual);
    let mut writer = encoder
        .write_header()
        .with_context(|| format!("writing {}", path.display()))?;
    writer
        .write_image_data(data)
        .with_context(|| format!("writing {}", path.display()))?;
    writer
        .finish()
        .with_context(|| format!("writing {}", path.display()))
}

/// Writes `frames` (one size) tone-mapped at `exposure` as an animated PNG (APNG) playing at
/// `fps` frames per second in a loop: what `irad render --sequence` previews, viewable in any
/// browser. Written under a temporary name and renamed.
pub fn write_animated(path: &Path, frames: &[Image], fps: f32, exposure: f32) -> Result<()> {
    let Some(first) = frames.first() else {
        anyhow::bail!("writing {}: no frames", path.display());
    };
    let (width, height) = (first.width, first.height);
    ensure!(
        frames
            .iter()
            .all(|f| (f.width, f.height) == (width, height)),
        "writing {}: the frames differ in size",
        path.display()
    );
    ensure!(
        fps.is_finite() && fps > 0.0,
        "writing {}: {fps} frames per second",
        path.display()
    );
    let tmp = path.with_extension("png.tmp");
    let write = || -> Result<()> {
        let file = File::create(&tmp)?;
        let mut encoder = ::png::Encoder::new(BufWriter::new(file), width, height);
        encoder.set_color(::png::ColorType::Rgb);
        encoder.set_depth(::png::BitDepth::Eight);
        encoder.set_source_srgb(::png::SrgbRenderingIntent::Perceptual);
        encoder.set_animated(frames.len() as u32, 0)?;
        // The delay as a fraction: 1000 / (1000 fps) seconds, to a millisecond's precision.
        let denominator = (fps * 1000.0).round().clamp(1.0, u16::MAX as f32) as u16;
        encoder.set_frame_delay(1000u16.min(denominator), denominator)?;
        let mut writer = encoder.write_header()?;
        for frame in frames {
            writer.write_image_data(&tonemap::tonemap_rgb8(frame, exposure))?;
        }
        writer.finish()?;
        Ok(())
    };
    write().with_context(|| format!("writing {}", tmp.display()))?;
    std::fs::rename(&tmp, path).with_context(|| format!("writing {}", path.display()))
}
