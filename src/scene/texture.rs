//! Albedo textures (docs/DESIGN.md "Textures"): PNG through the `png` crate (already irad's PNG
//! writer) and JPEG through `zune-jpeg` (pure Rust, two small crates), decoded to linear RGB
//! rounded to the half floats the GPU stores; and `Texture::sample`, the CPU mirror of
//! glsl/include/texture.glsl's bilinear lookup, for tests and CPU code.

use std::path::Path;

use glam::{Vec2, Vec3};
use half::f16;

use super::{Texture, Wrap};

/// The largest texture side irad reads: 16384 texels, the side most GPUs' 2D images allow;
/// a larger image is refused by name before it is decoded.
pub const MAX_SIDE: u32 = 16384;

/// Decodes a PNG or JPEG file's bytes (recognised by their signature, not the name) into a
/// texture. The error says what is wrong with the image; the caller names where it was
/// referenced.
pub fn decode(bytes: &[u8], source: &Path, wrap: [Wrap; 2]) -> Result<Texture, String> {
    let (width, height, rgb8) = if bytes.starts_with(b"\x89PNG\r\n\x1a\n") {
        decode_png(bytes)?
    } else if bytes.starts_with(&[0xff, 0xd8, 0xff]) {
        decode_jpeg(bytes)?
    } else {
        return Err("not a PNG or JPEG image (irad reads albedo textures in those two)".into());
    };
    let table = srgb_table();
    let texels = rgb8
        .chunks_exact(3)
        .map(|c| {
            Vec3::new(
                table[c[0] as usize],
                table[c[1] as usize],
                table[c[2] as usize],
            )
        })
        .collect();
    Ok(Texture {
        width,
        height,
        texels,
        wrap,
        source: source.to_path_buf(),
    })
}

fn check_side(width: u32, height: u32) -> Result<(), String> {
    if width == 0 || height == 0 {
        return Err(format!("the image is {width}x{height}"));
    }
    if width > MAX_SIDE || height > MAX_SIDE {
        return Err(format!(
            "the image is {width}x{height}; irad reads textures of at most {MAX_SIDE} texels a \
             side (scale it down)"
        ));
    }
    Ok(())
}

/// 8-bit RGB of any PNG: palettes and low bit depths expanded, 16 bits stripped to 8, grey
/// repeated, alpha dropped (irad has no alpha).
fn decode_png(bytes: &[u8]) -> Result<(u32, u32, Vec<u8>), String> {
    let mut decoder = png::Decoder::new(std::io::Cursor::new(bytes));
    decoder.set_transformations(png::Transformations::normalize_to_color8());
    let mut reader = decoder
        .read_info()
        .map_err(|e| format!("not a readable PNG: {e}"))?;
    let (width, height) = (reader.info().width, reader.info().height);
    check_side(width, height)?;
    let mut buffer = vec![0; reader.output_buffer_size().ok_or("PNG too large")?];
    let info = reader
        .next_frame(&mut buffer)
        .map_err(|e| format!("not a readable PNG: {e}"))?;
    let data = &buffer[..info.buffer_size()];
    let channels = info.color_type.samples();
    Ok((width, height, to_rgb(data, channels)?))
}

fn decode_jpeg(bytes: &[u8]) -> Result<(u32, u32, Vec<u8>), String> {
    use zune_jpeg::zune_core::{colorspace::ColorSpace, options::DecoderOptions};
    let options = DecoderOptions::default().jpeg_set_out_colorspace(ColorSpace::RGB);
    let mut decoder = zune_jpeg::JpegDecoder::new_with_options(bytes, options);
    decoder
        .decode_headers()
        .map_err(|e| format!("not a readable JPEG: {e:?}"))?;
    let (width, height) = decoder
        .dimensions()
        .map(|(w, h)| (w as u32, h as u32))
        .ok_or("not a readable JPEG: no dimensions")?;
    check_side(width, height)?;
    let data = decoder
        .decode()
        .map_err(|e| format!("not a readable JPEG: {e:?}"))?;
    if data.len() != 3 * width as usize * height as usize {
        return Err(format!(
            "the JPEG decoded to {} bytes, not {width}x{height} RGB",
            data.len()
        ));
    }
    Ok((width, height, data))
}

fn to_rgb(data: &[u8], channels: usize) -> Result<Vec<u8>, String> {
    Ok(match channels {
        1 => data.iter().flat_map(|&g| [g, g, g]).collect(),
        2 => data
            .chunks_exact(2)
            .flat_map(|c| [c[0], c[0], c[0]])
            .collect(),
        3 => data.to_vec(),
        4 => data
            .chunks_exact(4)
            .flat_map(|c| [c[0], c[1], c[2]])
            .collect(),
        n => return Err(format!("a PNG of {n} channels")),
    })
}

/// Each 8-bit sRGB code's linear value, rounded to half precision: `decode`'s table (strictly
/// increasing, so a decoded texel names its code: `srgb_code`).
pub fn srgb_table() -> [f32; 256] {
    std::array::from_fn(|i| {
        let c = i as f64 / 255.0;
        let linear = if c <= 0.04045 {
            c / 12.92
        } else {
            ((c + 0.055) / 1.055).powf(2.4)
        };
        f16::from_f64(linear).to_f32()
    })
}

/// The 8-bit code whose decoded value is nearest `linear` (clamped to [0, 1]): the code a
/// texel decoded from an 8-bit file came from.
pub fn srgb_code(table: &[f32; 256], linear: f32) -> u8 {
    let i = table.partition_point(|&t| t < linear);
    if i == 0 {
        return 0;
    }
    if i == 256 {
        return 255;
    }
    if linear - table[i - 1] <= table[i] - linear {
        (i - 1) as u8
    } else {
        i as u8
    }
}

/// A texel index on one axis: `i` wrapped into 0..n.
fn wrap_index(i: i64, n: u32, wrap: Wrap) -> u32 {
    let n = n as i64;
    (match wrap {
        Wrap::Repeat => i.rem_euclid(n),
        Wrap::Clamp => i.clamp(0, n - 1),
        Wrap::Mirror => {
            let k = i.rem_euclid(2 * n);
            if k < n {
                k
            } else {
                2 * n - 1 - k
            }
        }
    }) as u32
}

impl Texture {
    /// The bilinear value at `uv` (OBJ's convention, v up): glsl/include/texture.glsl's
    /// `sample_texture`, in the same f32 operations (a driver may fuse a multiply and an add,
    /// so the kernels' value may differ in the last bits). Repeat and mirror wrap take `uv` mod 1
    /// first (mirror's period is 2 texture widths, so `uv`'s integer part is kept for it).
    pub fn sample(&self, uv: Vec2) -> Vec3 {
        let x = axis(uv.x, self.width, self.wrap[0]);
        let y = axis(1.0 - uv.y, self.height, self.wrap[1]);
        let (x0, fx) = (x.floor(), x - x.floor());
        let (y0, fy) = (y.floor(), y - y.floor());
        let texel = |i: f32, j: f32| {
            let i = wrap_index(i as i64, self.width, self.wrap[0]);
            let j = wrap_index(j as i64, self.height, self.wrap[1]);
            self.texels[(j * self.width + i) as usize]
        };
        let top = texel(x0, y0) * (1.0 - fx) + texel(x0 + 1.0, y0) * fx;
        let bottom = texel(x0, y0 + 1.0) * (1.0 - fx) + texel(x0 + 1.0, y0 + 1.0) * fx;
        top * (1.0 - fy) + bottom * fy
    }
}

/// The continuous texel coordinate on one axis (u, or 1 - v: rows from the top), texel centres
/// at half-integers: repeat reduces `t` mod 1 and mirror mod 2 (`wrap_index` then mirrors the
/// texel indices), clamp's is clamped to [-1, n] (`wrap_index` then clamps the indices).
fn axis(t: f32, n: u32, wrap: Wrap) -> f32 {
    match wrap {
        Wrap::Repeat => (t - t.floor()) * n as f32 - 0.5,
        Wrap::Mirror => {
            let t2 = t - 2.0 * (0.5 * t).floor();
            t2 * n as f32 - 0.5
        }
        Wrap::Clamp => (t * n as f32 - 0.5).clamp(-1.0, n as f32),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn texture(width: u32, height: u32, wrap: Wrap) -> Texture {
        Texture {
            width,
            height,
            texels: (0..width * height).map(|i| Vec3::splat(i as f32)).collect(),
            wrap: [wrap; 2],
            source: "t.png".into(),
        }
    }

    #[test]
    fn texel_centres_give_their_texel_and_between_is_linear() {
        let t = texture(4, 2, Wrap::Repeat);
        // Texel (1, 0): u centre 1.5 / 4, row 0 is the top (v = 1 - 0.5 / 2).
        assert_eq!(t.sample(Vec2::new(1.5 / 4.0, 0.75)).x, 1.0);
        assert_eq!(t.sample(Vec2::new(2.0 / 4.0, 0.75)).x, 1.5);
        // Row 1 (bottom) of texel 1 is 5; halfway between rows: 3.
        assert_eq!(t.sample(Vec2::new(1.5 / 4.0, 0.25)).x, 5.0);
        assert_eq!(t.sample(Vec2::new(1.5 / 4.0, 0.5)).x, 3.0);
    }

    #[test]
    fn wraps_repeat_mirror_and_clamp() {
        let repeat = texture(4, 1, Wrap::Repeat);
        // Between texel 3 and texel 0 across the edge.
        assert_eq!(repeat.sample(Vec2::new(1.0, 0.5)).x, 1.5);
        assert_eq!(repeat.sample(Vec2::new(3.0 + 1.5 / 4.0, 0.5)).x, 1.0);
        let clamp = texture(4, 1, Wrap::Clamp);
        assert_eq!(clamp.sample(Vec2::new(1.0, 0.5)).x, 3.0);
        assert_eq!(clamp.sample(Vec2::new(-7.0, 0.5)).x, 0.0);
        let mirror = texture(4, 1, Wrap::Mirror);
        // Past the right edge the texels run 3, 2, 1, 0.
        assert_eq!(mirror.sample(Vec2::new(1.0 + 0.5 / 4.0, 0.5)).x, 3.0);
        assert_eq!(mirror.sample(Vec2::new(1.0 + 1.5 / 4.0, 0.5)).x, 2.0);
        assert_eq!(mirror.sample(Vec2::new(1.0, 0.5)).x, 3.0);
    }

    #[test]
    fn png_and_jpeg_decode_and_other_files_are_refused() {
        let dir = std::env::temp_dir().join(format!("irad-texture-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("t.png");
        crate::image::png::write_rgb8(&path, 2, 1, &[255, 0, 0, 0, 128, 255]).unwrap();
        let t = decode(&std::fs::read(&path).unwrap(), &path, [Wrap::Repeat; 2]).unwrap();
        assert_eq!((t.width, t.height), (2, 1));
        assert_eq!(t.texels[0], Vec3::new(1.0, 0.0, 0.0));
        // sRGB 128 is linear 0.2158605, as a half 0.2158203.
        assert!((t.texels[1].y - 0.21582).abs() < 1e-5, "{}", t.texels[1].y);
        assert_eq!(t.texels[1].z, 1.0);
        let e = decode(b"GIF89a", &path, [Wrap::Repeat; 2]).unwrap_err();
        assert!(e.contains("not a PNG or JPEG"), "{e}");
        let e = decode(&[0xff, 0xd8, 0xff, 0xe0, 0, 0], &path, [Wrap::Repeat; 2]).unwrap_err();
        assert!(e.contains("JPEG"), "{e}");
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
