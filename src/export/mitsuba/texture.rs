//! Albedo textures as Mitsuba `bitmap` reflectances. irad's material is Kd times the texture;
//! Mitsuba 3's core plugins have no texture product, so the diffuse reflectance the BSDF
//! writes (Kd, or Kd / (1 - w) in a glossy blend, bsdf.rs) becomes:
//! - 1: the bitmap itself;
//! - a grey g < 1: `blendbsdf` of weight g between a black `diffuse` and the bitmap's
//!   (exact: Mitsuba's blend is (1 - g) 0 + g T);
//! - any other colour: the bitmap with the colour baked in, `mesh-NNN-NAME-albedo.png` (8-bit
//!   sRGB: each texel within half a code of irad's), an approximation.
//!
//! The bitmap is the texture's own file, copied beside the XML as `texture-NNN-NAME.png` (or
//! `.jpg`), when it is a PNG or JPEG that still decodes to the texture's texels; else the
//! texels written as an 8-bit sRGB PNG (exact for texels decoded from 8-bit files; others
//! rounded, with a note). Mitsuba has one `wrap_mode` for both axes: a texture whose two
//! axes wrap differently is written with u's, with a note. Texture coordinates: the meshes
//! carry irad's (v up) and their shapes `flip_tex_coords` (mitsuba.rs), so Mitsuba reads the
//! image the right way up.

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use glam::Vec3;

use super::{file_stem, ExportError};
use crate::scene::texture::{srgb_code, srgb_table};
use crate::scene::{Scene, Texture, Wrap};

/// How a material's diffuse reflectance reads its texture.
#[derive(Clone, Debug, PartialEq)]
pub struct Bitmap {
    /// The image file, relative to the XML.
    pub file: String,
    pub wrap_mode: &'static str,
    /// A grey factor < 1 written as a blend with black; None for the bitmap alone.
    pub blend: Option<f32>,
}

/// The texture files written so far (each scene texture copied or written once).
#[derive(Default)]
pub struct TextureFiles {
    written: HashMap<u32, String>,
    /// Every file written, in order.
    pub files: Vec<PathBuf>,
}

pub fn wrap_mode(w: Wrap) -> &'static str {
    match w {
        Wrap::Repeat => "repeat",
        Wrap::Mirror => "mirror",
        Wrap::Clamp => "clamp",
    }
}

impl TextureFiles {
    /// The bitmap for scene texture `index` times the diffuse reflectance `factor` of the
    /// material whose mesh is `mesh` (`DIR/mesh.ply`), and notes on what is approximate.
    pub fn reflectance(
        &mut self,
        scene: &Scene,
        index: u32,
        factor: [f64; 3],
        dir: &Path,
        mesh: &str,
        material: &str,
    ) -> Result<(Bitmap, Vec<String>), ExportError> {
        let mut notes = Vec::new();
        let texture = &scene.textures[index as usize];
        if texture.wrap[0] != texture.wrap[1] {
            notes.push(format!(
                "material `{material}`: its texture wraps u {} and v {}; Mitsuba's bitmap has \
                 one wrap_mode, written as u's",
                wrap_mode(texture.wrap[0]),
                wrap_mode(texture.wrap[1])
            ));
        }
        let wrap_mode = wrap_mode(texture.wrap[0]);
        let grey = factor[0] == factor[1] && factor[1] == factor[2];
        if grey && factor[0] > 0.0 && factor[0] <= 1.0 {
            let file = self.original(scene, index, dir, &mut notes)?;
            let blend = (factor[0] < 1.0).then_some(factor[0] as f32);
            let bitmap = Bitmap {
                file,
                wrap_mode,
                blend,
            };
            return Ok((bitmap, notes));
        }
        let file = format!("{mesh}-albedo.png");
        let path = dir.join(&file);
        let factor = Vec3::from(factor.map(|c| c as f32));
        let clamped = write_png(&path, texture, factor)?;
        self.files.push(path);
        notes.push(format!(
            "material `{material}`: Kd {} times its texture baked into {file} (Mitsuba has no \
             texture product): 8-bit sRGB, each texel within half a code of irad's{}",
            super::list(factor),
            if clamped.is_empty() {
                String::new()
            } else {
                format!("; {clamped}")
            }
        ));
        let bitmap = Bitmap {
            file,
            wrap_mode,
            blend: None,
        };
        Ok((bitmap, notes))
    }

    /// Scene texture `index` beside the XML: its file copied, or its texels as a PNG.
    fn original(
        &mut self,
        scene: &Scene,
        index: u32,
        dir: &Path,
        notes: &mut Vec<String>,
    ) -> Result<String, ExportError> {
        if let Some(f) = self.written.get(&index) {
            return Ok(f.clone());
        }
        let texture = &scene.textures[index as usize];
        let stem = texture
            .source
            .file_stem()
            .map(|s| file_stem(&s.to_string_lossy()))
            .unwrap_or_else(|| "texture".into());
        let name = format!("texture-{index:03}-{stem}");
        let file = match same_file(texture) {
            Some((bytes, extension)) => {
                let file = format!("{name}.{extension}");
                let path = dir.join(&file);
                std::fs::write(&path, bytes).map_err(|error| ExportError::Write {
                    path: path.display().to_string(),
                    what: format!("copy of texture {}", texture.source.display()),
                    error,
                })?;
                self.files.push(path);
                file
            }
            None => {
                let file = format!("{name}.png");
                let path = dir.join(&file);
                let rounded = write_png(&path, texture, Vec3::ONE)?;
                self.files.push(path);
                if !rounded.is_empty() {
                    notes.push(format!(
                        "texture {index} ({}): written as {file}, {rounded}",
                        texture.source.display()
                    ));
                }
                file
            }
        };
        self.written.insert(index, file.clone());
        Ok(file)
    }
}

/// The texture's source file and its extension, when it is a PNG or JPEG that decodes to the
/// texture's texels.
fn same_file(texture: &Texture) -> Option<(Vec<u8>, &'static str)> {
    let bytes = std::fs::read(&texture.source).ok()?;
    let extension = if bytes.starts_with(b"\x89PNG\r\n\x1a\n") {
        "png"
    } else if bytes.starts_with(&[0xff, 0xd8, 0xff]) {
        "jpg"
    } else {
        return None;
    };
    let decoded = crate::scene::texture::decode(&bytes, &texture.source, texture.wrap).ok()?;
    let same = (decoded.width, decoded.height) == (texture.width, texture.height)
        && decoded.texels == texture.texels;
    same.then_some((bytes, extension))
}

/// Writes `factor` times the texture's texels as an 8-bit sRGB PNG (each channel the code
/// whose decoded value is nearest); returns what was not exact ("" when every texel decodes
/// back to its value).
fn write_png(path: &Path, texture: &Texture, factor: Vec3) -> Result<String, ExportError> {
    let table = srgb_table();
    let (mut clamped, mut rounded) = (0usize, 0usize);
    let mut data = Vec::with_capacity(3 * texture.texels.len());
    for t in &texture.texels {
        let v = *t * factor;
        clamped += usize::from(v.max_element() > 1.0 || v.min_element() < 0.0);
        for c in v.to_array() {
            let code = srgb_code(&table, c);
            rounded += usize::from(table[code as usize] != c);
            data.push(code);
        }
    }
    crate::image::png::write_rgb8(path, texture.width, texture.height, &data).map_err(|e| {
        ExportError::Texture {
            path: path.display().to_string(),
            message: format!("{e:#}"),
        }
    })?;
    let mut out = Vec::new();
    if factor == Vec3::ONE && rounded > 0 {
        out.push(format!(
            "{rounded} channels rounded to 8-bit sRGB (the texture was not read from an 8-bit \
             file)"
        ));
    }
    if clamped > 0 {
        out.push(format!("{clamped} texels outside [0, 1] clamped"));
    }
    Ok(out.join(", "))
}
