//! Mitsuba `bitmap` textures, until irad renders textures (docs/scenes.md "Mitsuba scenes"): each stands in
//! as its mean linear colour, with a warning. PNG (8 or 16 bits, sRGB-decoded unless `raw`)
//! and EXR are read; other formats are refused by name.

use glam::{DVec3, Vec3};
use roxmltree::Node;

use super::props::Context;
use crate::scene::SceneError;

/// The mean linear colour of the `<texture type="bitmap">` element `node`.
pub fn mean(ctx: &Context, node: Node, warnings: &mut Vec<String>) -> Result<Vec3, SceneError> {
    let kind = ctx.attr(node, "type").unwrap_or_default();
    if kind != "bitmap" {
        return Err(ctx.invalid(node, &kind, "only bitmap textures are read"));
    }
    let file_node = node
        .children()
        .find(|c| c.is_element() && c.attribute("name") == Some("filename"))
        .ok_or_else(|| ctx.invalid(node, "", "a bitmap needs <string name=\"filename\">"))?;
    let name = ctx.required(file_node, "value")?;
    let raw = node
        .children()
        .find(|c| c.is_element() && c.attribute("name") == Some("raw"))
        .and_then(|c| ctx.attr(c, "value"))
        .is_some_and(|v| v == "true");
    let path = ctx.base.join(&name);
    let bytes = std::fs::read(&path).map_err(|error| SceneError::Read {
        path: path.display().to_string(),
        referenced_by: format!("{}: {}", ctx.file, ctx.at(file_node)),
        error,
    })?;
    ctx.hash.borrow_mut().write(&bytes);
    let lower = name.to_ascii_lowercase();
    let mean = if lower.ends_with(".png") {
        png_mean(&bytes, !raw)
    } else if lower.ends_with(".exr") {
        crate::image::exr::read(&path)
            .map_err(|e| format!("{e:#}"))
            .map(|im| {
                let sum = im
                    .pixels
                    .iter()
                    .fold(DVec3::ZERO, |s, p| s + Vec3::from(*p).as_dvec3());
                sum / im.pixels.len().max(1) as f64
            })
    } else {
        Err("only PNG and EXR textures are read".to_string())
    }
    .map_err(|message| SceneError::File {
        file: path.display().to_string(),
        message: format!("{message} (bitmap at {} of {})", ctx.at(node), ctx.file),
    })?;
    let mean = mean.as_vec3();
    warnings.push(format!(
        "{}: {}: texture {name} as its mean colour {mean} (irad does not render textures yet)",
        ctx.file,
        ctx.at(node)
    ));
    Ok(mean)
}

fn png_mean(bytes: &[u8], srgb: bool) -> Result<DVec3, String> {
    let mut decoder = png::Decoder::new(std::io::Cursor::new(bytes));
    decoder.set_transformations(png::Transformations::EXPAND);
    let mut reader = decoder.read_info().map_err(|e| e.to_string())?;
    let mut buf = vec![0; reader.output_buffer_size().ok_or("too large")?];
    let info = reader.next_frame(&mut buf).map_err(|e| e.to_string())?;
    let channels = info.color_type.samples();
    let wide = info.bit_depth == png::BitDepth::Sixteen;
    let max = if wide { 65535.0 } else { 255.0 };
    let data = &buf[..info.buffer_size()];
    let sample = |i: usize| -> f64 {
        let v = if wide {
            u16::from_be_bytes([data[2 * i], data[2 * i + 1]]) as f64
        } else {
            data[i] as f64
        } / max;
        if srgb {
            if v <= 0.04045 {
                v / 12.92
            } else {
                ((v + 0.055) / 1.055).powf(2.4)
            }
        } else {
            v
        }
    };
    let pixels = (info.width * info.height) as usize;
    let mut sum = DVec3::ZERO;
    for p in 0..pixels {
        let o = p * channels;
        sum += match channels {
            1 | 2 => DVec3::splat(sample(o)),
            _ => DVec3::new(sample(o), sample(o + 1), sample(o + 2)),
        };
    }
    Ok(sum / pixels.max(1) as f64)
}
