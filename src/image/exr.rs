//! OpenEXR in and out through the `exr` crate: float32 linear RGB.

use std::path::Path;

use anyhow::{Context, Result};

use super::Image;

/// Writes `image` as float32 RGB.
pub fn write(path: &Path, image: &Image) -> Result<()> {
    let w = image.width as usize;
    ::exr::prelude::write_rgb_file(path, w, image.height as usize, |x, y| {
        let p = image.pixels[y * w + x];
        (p[0], p[1], p[2])
    })
    .with_context(|| format!("writing {}", path.display()))
}

/// Reads the first RGB(A) layer at its largest resolution, as f32 (alpha ignored). Values are
/// returned as stored: callers decide what NaN, Inf or negative values mean for them.
pub fn read(path: &Path) -> Result<Image> {
    let image = ::exr::prelude::read_first_rgba_layer_from_file(
        path,
        |resolution, _| Image::new(resolution.width() as u32, resolution.height() as u32),
        |image: &mut Image, position, (r, g, b, _a): (f32, f32, f32, f32)| {
            let i = position.y() * image.width as usize + position.x();
            image.pixels[i] = [r, g, b];
        },
    )
    .with_context(|| format!("reading {} as an RGB OpenEXR image", path.display()))?;
    Ok(image.layer_data.channel_data.pixels)
}
