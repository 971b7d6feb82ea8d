//! Mitsuba `bitmap` textures (docs/scenes.md "Mitsuba scenes"). A bitmap as a diffuse
//! reflectance becomes an irad albedo texture (`Albedo`): PNG and JPEG through
//! `scene::texture::decode` (8-bit, sRGB-decoded; with `raw="true"` the decoded texels are
//! taken back to code / 255, linear as Mitsuba reads them), EXR as its linear texels;
//! `wrap_mode` as irad's wrap on both axes, `filter_type` ignored (irad is bilinear, as
//! Mitsuba's default), a `to_uv` of scales and translations applied to the shape's texture
//! coordinates (anything else left out, with a warning). Elsewhere (specular reflectance,
//! roughness, blend weights) and where irad's material cannot hold the texture exactly, a
//! bitmap stands in as its mean linear colour, with a warning (`mean`, `Albedo::flatten`).
//!
//! Mitsuba's texture coordinates have v = 0 at the image's top row (its bitmap lookup reads
//! row v H - 1/2 from the top, no flip), irad's at the bottom row (OBJ's convention): irad's
//! v is 1 - Mitsuba's v, which is what shapes.rs produces for every shape.

use std::path::PathBuf;
use std::rc::Rc;

use glam::{DVec3, Vec2, Vec3};
use half::f16;
use roxmltree::Node;

use super::props::Context;
use crate::scene::texture::{srgb_code, srgb_table, MAX_SIDE};
use crate::scene::{SceneError, Texture, Wrap};

/// A bitmap's image, decoded once per file and `raw` flag (`Context::textures`).
#[derive(Debug)]
pub struct Image {
    /// Linear texels (half-rounded) with repeat wrap; the scene's copy gets its own wrap.
    pub texture: Texture,
    /// The mean linear colour.
    pub mean: Vec3,
}

/// A `to_uv` of scales and translations: Mitsuba's (u, v) -> (scale u + offset) per axis, in
/// Mitsuba's convention (v down).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct UvMap {
    pub scale: [f64; 2],
    pub offset: [f64; 2],
}

impl UvMap {
    pub const IDENTITY: UvMap = UvMap {
        scale: [1.0, 1.0],
        offset: [0.0, 0.0],
    };

    /// The map on irad's coordinates (v up: irad's v is 1 - Mitsuba's): u' = a u + b,
    /// v' = 1 - (c (1 - v) + d) = c v + (1 - c - d). The identity keeps every bit.
    pub fn apply(&self, uv: Vec2) -> Vec2 {
        if *self == UvMap::IDENTITY {
            return uv;
        }
        let [a, c] = self.scale;
        let [b, d] = self.offset;
        Vec2::new(
            (a * uv.x as f64 + b) as f32,
            (c * uv.y as f64 + (1.0 - c - d)) as f32,
        )
    }
}

/// A bitmap read as an albedo texture.
#[derive(Clone, Debug)]
pub struct Albedo {
    /// The image file, relative to nothing (the XML's folder joined).
    pub path: PathBuf,
    pub raw: bool,
    pub wrap: [Wrap; 2],
    pub uv: UvMap,
    pub image: Rc<Image>,
    /// The filename as the XML gives it, and where the bitmap is, for warnings.
    pub name: String,
    pub at: String,
}

impl PartialEq for Albedo {
    /// The same texture on the same coordinates.
    fn eq(&self, other: &Self) -> bool {
        (&self.path, self.raw, self.wrap, self.uv) == (&other.path, other.raw, other.wrap, other.uv)
    }
}

impl Albedo {
    /// `factor` times the texture's mean, with a warning saying why the texture is not kept.
    pub fn flatten(
        &self,
        ctx: &Context,
        factor: Vec3,
        why: &str,
        warnings: &mut Vec<String>,
    ) -> Vec3 {
        warnings.push(format!(
            "{}: {}: texture {} as its mean colour {} ({why})",
            ctx.file, self.at, self.name, self.image.mean
        ));
        factor * self.image.mean
    }
}

fn child<'a, 'i>(node: Node<'a, 'i>, name: &str) -> Option<Node<'a, 'i>> {
    node.children()
        .find(|c| c.is_element() && c.attribute("name") == Some(name))
}

/// The `<texture type="bitmap">` element `node` as an albedo texture.
pub fn albedo(ctx: &Context, node: Node, warnings: &mut Vec<String>) -> Result<Albedo, SceneError> {
    let kind = ctx.attr(node, "type").unwrap_or_default();
    if kind != "bitmap" {
        return Err(ctx.invalid(node, &kind, "only bitmap textures are read"));
    }
    let file_node = child(node, "filename")
        .ok_or_else(|| ctx.invalid(node, "", "a bitmap needs <string name=\"filename\">"))?;
    let name = ctx.required(file_node, "value")?;
    let raw = child(node, "raw")
        .and_then(|c| ctx.attr(c, "value"))
        .is_some_and(|v| v == "true");
    let wrap = match child(node, "wrap_mode") {
        None => Wrap::Repeat,
        Some(w) => match ctx.required(w, "value")?.as_str() {
            "repeat" => Wrap::Repeat,
            "mirror" => Wrap::Mirror,
            "clamp" => Wrap::Clamp,
            other => return Err(ctx.invalid(w, other, "wrap_mode is repeat, mirror or clamp")),
        },
    };
    if let Some(f) = child(node, "filter_type") {
        if ctx.attr(f, "value").as_deref() == Some("nearest") {
            warnings.push(format!(
                "{}: {}: filter_type nearest read as bilinear (irad's one filter)",
                ctx.file,
                ctx.at(f)
            ));
        }
    }
    let uv = match node
        .children()
        .find(|c| c.has_tag_name("transform") && c.attribute("name") == Some("to_uv"))
    {
        Some(t) => uv_map(ctx, t, warnings)?,
        None => UvMap::IDENTITY,
    };
    let path = ctx.base.join(&name);
    let key = (path.clone(), raw);
    let cached = ctx.textures.borrow().get(&key).cloned();
    let image = match cached {
        Some(image) => image,
        None => {
            let image = Rc::new(read(ctx, node, file_node, &name, &path, raw)?);
            ctx.textures.borrow_mut().insert(key, image.clone());
            image
        }
    };
    Ok(Albedo {
        path,
        raw,
        wrap: [wrap; 2],
        uv,
        image,
        name,
        at: ctx.at(node),
    })
}

/// The mean linear colour of the `<texture type="bitmap">` element `node`, with a warning.
pub fn mean(ctx: &Context, node: Node, warnings: &mut Vec<String>) -> Result<Vec3, SceneError> {
    let a = albedo(ctx, node, warnings)?;
    Ok(a.flatten(
        ctx,
        Vec3::ONE,
        "irad's textures are albedo textures on the diffuse part",
        warnings,
    ))
}

/// A `to_uv` transform of `scale` and `translate` steps (Mitsuba's order: each after the
/// ones before it); anything else leaves the coordinates as they are, with a warning.
fn uv_map(ctx: &Context, t: Node, warnings: &mut Vec<String>) -> Result<UvMap, SceneError> {
    let mut m = UvMap::IDENTITY;
    for op in t.children().filter(|c| c.is_element()) {
        let (s, o) = match op.tag_name().name() {
            "scale" => {
                let v = ctx.vector(op, 1.0)?;
                ([v.x, v.y], [0.0, 0.0])
            }
            "translate" => {
                let v = ctx.vector(op, 0.0)?;
                ([1.0, 1.0], [v.x, v.y])
            }
            other => {
                warnings.push(format!(
                    "{}: {}: a to_uv with <{other}> is left out (irad reads scale and \
                     translate): the texture is read on the shape's own coordinates",
                    ctx.file,
                    ctx.at(t)
                ));
                return Ok(UvMap::IDENTITY);
            }
        };
        for k in 0..2 {
            m.scale[k] *= s[k];
            m.offset[k] = s[k] * m.offset[k] + o[k];
        }
    }
    Ok(m)
}

/// Reads and decodes the bitmap file `path` (its bytes go into the content hash).
fn read(
    ctx: &Context,
    node: Node,
    file_node: Node,
    name: &str,
    path: &std::path::Path,
    raw: bool,
) -> Result<Image, SceneError> {
    let bytes = std::fs::read(path).map_err(|error| SceneError::Read {
        path: path.display().to_string(),
        referenced_by: format!("{}: {}", ctx.file, ctx.at(file_node)),
        error,
    })?;
    ctx.hash.borrow_mut().write(&bytes);
    let texture = if name.to_ascii_lowercase().ends_with(".exr") {
        exr_texture(path)
    } else {
        crate::scene::texture::decode(&bytes, path, [Wrap::Repeat; 2]).map(|mut t| {
            if raw {
                t.texels = t.texels.iter().map(|&v| undo_srgb(v)).collect();
            }
            t
        })
    }
    .map_err(|message| SceneError::File {
        file: path.display().to_string(),
        message: format!("{message} (bitmap at {} of {})", ctx.at(node), ctx.file),
    })?;
    let sum = texture
        .texels
        .iter()
        .fold(DVec3::ZERO, |s, t| s + t.as_dvec3());
    let mean = (sum / texture.texels.len().max(1) as f64).as_vec3();
    Ok(Image { texture, mean })
}

/// An OpenEXR image as a texture: its linear texels, rounded to half floats.
fn exr_texture(path: &std::path::Path) -> Result<Texture, String> {
    let image = crate::image::exr::read(path).map_err(|e| format!("{e:#}"))?;
    if image.width == 0 || image.height == 0 || image.width > MAX_SIDE || image.height > MAX_SIDE {
        return Err(format!(
            "the image is {}x{}; irad reads textures of 1 to {MAX_SIDE} texels a side",
            image.width, image.height
        ));
    }
    let half = |c: f32| f16::from_f32(c).to_f32();
    let texels: Vec<Vec3> = image
        .pixels
        .iter()
        .map(|p| Vec3::from(p.map(half)))
        .collect();
    if let Some(bad) = texels
        .iter()
        .find(|t| !(t.is_finite() && t.min_element() >= 0.0))
    {
        return Err(format!(
            "a texel is {bad} (as a half float): albedo texels must be finite and >= 0"
        ));
    }
    Ok(Texture {
        width: image.width,
        height: image.height,
        texels,
        wrap: [Wrap::Repeat; 2],
        source: path.to_path_buf(),
    })
}

/// A texel `decode` took through the sRGB curve, as the code / 255 a `raw` bitmap means.
fn undo_srgb(v: Vec3) -> Vec3 {
    thread_local! {
        static TABLE: [f32; 256] = srgb_table();
    }
    TABLE.with(|table| {
        Vec3::from(
            v.to_array()
                .map(|c| f16::from_f64(srgb_code(table, c) as f64 / 255.0).to_f32()),
        )
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn uv_maps_act_in_mitsubas_convention() {
        let m = UvMap {
            scale: [2.0, 4.0],
            offset: [0.25, 0.5],
        };
        // Mitsuba's (0.1, 0.2) is irad's (0.1, 0.8); mapped, Mitsuba's (0.45, 1.3): irad's
        // v = 1 - 1.3.
        let out = m.apply(Vec2::new(0.1, 0.8));
        assert!((out - Vec2::new(0.45, -0.3)).length() < 1e-6, "{out}");
        let v = Vec2::new(0.3, 0.7);
        assert_eq!(UvMap::IDENTITY.apply(v), v);
    }

    #[test]
    fn srgb_codes_invert_the_decode_table() {
        let table = srgb_table();
        for (c, &t) in table.iter().enumerate() {
            assert_eq!(srgb_code(&table, t), c as u8);
        }
        assert_eq!(srgb_code(&table, -1.0), 0);
        assert_eq!(srgb_code(&table, 7.0), 255);
        assert!(table.windows(2).all(|w| w[0] < w[1]));
        // The table is scene::texture::decode's.
        let dir = std::env::temp_dir().join(format!("irad-mitsuba-srgb-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("codes.png");
        let codes: Vec<u8> = (0..=255u8).flat_map(|c| [c, c, c]).collect();
        crate::image::png::write_rgb8(&path, 256, 1, &codes).unwrap();
        let bytes = std::fs::read(&path).unwrap();
        let t = crate::scene::texture::decode(&bytes, &path, [Wrap::Repeat; 2]).unwrap();
        for (c, texel) in t.texels.iter().enumerate() {
            assert_eq!(texel.x, table[c], "code {c}");
            assert_eq!(
                undo_srgb(*texel).x,
                f16::from_f64(c as f64 / 255.0).to_f32()
            );
        }
        std::fs::remove_dir_all(&dir).ok();
    }
}
