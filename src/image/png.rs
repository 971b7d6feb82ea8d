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

/// The APNG frame delay num / den seconds closest to 1 / fps with both in 1..=65535 (whole rates
/// exactly: 1 / 24), found by trying every numerator. Browsers play delays of 10 ms or less as
/// 100 ms, so rates of 100 fps and more do not play at their rate in them.
pub fn frame_delay(fps: f32) -> (u16, u16) {
    let fps = fps as f64;
    let mut best = (1u16, 1u16, f64::INFINITY);
    for num in 1..=65535u32 {
        let den = (num as f64 * fps).round();
        if !(1.0..=65535.0).contains(&den) {
            continue;
        }
        let error = (den / num as f64 / fps - 1.0).abs();
        if error < best.2 {
            best = (num as u16, den as u16, error);
        }
    }
    (best.0, best.1)
}

/// Writes `count` frames, `frame(i)` each (one size), tone-mapped at `exposure` as an animated
/// PNG (APNG) playing at `fps` frames per second in a loop: what `irad render --sequence`
/// previews, viewable in any browser. One frame is in memory at a time. Written under a
/// temporary name and renamed.
pub fn write_animated(
    path: &Path,
    count: usize,
    mut frame: impl FnMut(usize) -> Result<Image>,
    fps: f32,
    exposure: f32,
) -> Result<()> {
    ensure!(count > 0, "writing {}: no frames", path.display());
    ensure!(
        fps.is_finite() && fps > 0.0,
        "writing {}: {fps} frames per second",
        path.display()
    );
    let tmp = path.with_extension("png.tmp");
    let mut write = || -> Result<()> {
        let first = frame(0)?;
        let (width, height) = (first.width, first.height);
        let file = File::create(&tmp)?;
        let mut encoder = ::png::Encoder::new(BufWriter::new(file), width, height);
        encoder.set_color(::png::ColorType::Rgb);
        encoder.set_depth(::png::BitDepth::Eight);
        encoder.set_source_srgb(::png::SrgbRenderingIntent::Perceptual);
        encoder.set_animated(count as u32, 0)?;
        let (num, den) = frame_delay(fps);
        encoder.set_frame_delay(num, den)?;
        let mut writer = encoder.write_header()?;
        writer.write_image_data(&tonemap::tonemap_rgb8(&first, exposure))?;
        for i in 1..count {
            let image = frame(i)?;
            ensure!(
                (image.width, image.height) == (width, height),
                "frame {i} is {}x{}, frame 0 {width}x{height}",
                image.width,
                image.height
            );
            writer.write_image_data(&tonemap::tonemap_rgb8(&image, exposure))?;
        }
        writer.finish()?;
        Ok(())
    };
    write().with_context(|| format!("writing {}", tmp.display()))?;
    std::fs::rename(&tmp, path).with_context(|| format!("writing {}", path.display()))
}

#[cfg(test)]
mod tests {
    use super::frame_delay;

    #[test]
    fn frame_delays_are_the_rate_closest_to_asked() {
        assert_eq!(frame_delay(24.0), (1, 24));
        assert_eq!(frame_delay(120.0), (1, 120));
        for fps in [23.976f32, 0.5, 0.01, 29.97, 1000.5] {
            let (n, d) = frame_delay(fps);
            let played = d as f64 / n as f64;
            assert!((played / fps as f64 - 1.0).abs() < 1e-5, "{fps}: {n}/{d}");
        }
    }
}
