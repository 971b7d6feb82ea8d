//! The JSON record beside every render (DESIGN.md "Outputs"): what was rendered, how, on what,
//! how long each pass took and, when a reference was given, how far from it. Also where the
//! three outputs of `-o <out>` go, and writing all three.

use std::collections::BTreeMap;
use std::ffi::OsString;
use std::fs;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result};
use serde::{Deserialize, Serialize};

use super::metrics::Metrics;
use super::{exr, png, Image};

/// This build's version, for `RenderRecord::irad_version`.
pub const IRAD_VERSION: &str = env!("CARGO_PKG_VERSION");

/// One render, as written to `<out>.json`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RenderRecord {
    /// Method name as given on the command line (`reference`, `ir`, ...).
    pub method: String,
    /// The method's parameters by name, sorted so records diff cleanly.
    pub parameters: BTreeMap<String, serde_json::Value>,
    /// Scene file path, or `embedded:cornell-box` for the built-in scene.
    pub scene: String,
    /// Content hash of the scene and its assets, 16 hex digits.
    pub scene_hash: String,
    /// [width, height] in pixels.
    pub resolution: [u32; 2],
    pub seed: u64,
    /// Samples as the method counts them: samples per pixel, VPLs, frames.
    pub samples: u64,
    /// Device name and driver as Vulkan reports them.
    pub device: String,
    pub driver: String,
    /// "forced" when every buffer went through staging copies (IRAD_FORCE_STAGING).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub staging: Option<String>,
    /// GPU time per pass, in the order the passes first ran.
    pub passes: Vec<PassRecord>,
    /// Sum of the passes' GPU times; `None` when the device has no timestamps.
    pub gpu_ms_total: Option<f64>,
    /// Wall-clock time of the render, upload to readback.
    pub wall_ms: f64,
    /// Error against the reference, when one was given.
    #[serde(default)]
    pub metrics: Option<Metrics>,
    #[serde(default)]
    pub warnings: Vec<String>,
    /// Method-specific figures (bir: fractions of kept VPLs per side, rays per kept VPL).
    #[serde(default)]
    pub stats: BTreeMap<String, f64>,
    pub irad_version: String,
}

/// The GPU time of one pass, summed over its `count` dispatches.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PassRecord {
    pub name: String,
    /// `None` when the device has no timestamps on the compute queue.
    pub gpu_ms: Option<f64>,
    pub count: u32,
}

impl RenderRecord {
    /// Writes the record as pretty-printed UTF-8 JSON with a final newline.
    pub fn write(&self, path: &Path) -> Result<()> {
        let mut text = serde_json::to_string_pretty(self)
            .with_context(|| format!("serializing the render record for {}", path.display()))?;
        text.push('\n');
        fs::write(path, text).with_context(|| format!("writing {}", path.display()))
    }

    pub fn read(path: &Path) -> Result<RenderRecord> {
        let text =
            fs::read_to_string(path).with_context(|| format!("reading {}", path.display()))?;
        serde_json::from_str(&text)
            .with_context(|| format!("parsing {} as an irad render record", path.display()))
    }
}

/// The EXR, PNG and JSON paths for `-o <out>`: the extensions are appended to `out`
/// (`out/cornell` gives `out/cornell.exr`, `out/cornell.png`, `out/cornell.json`; a dot in the
/// stem is kept). When `out` already ends in `.exr`, `.png` or `.json` that extension is
/// dropped first, so `-o out/cornell.png` does not give `out/cornell.png.png`.
pub fn output_paths(out: &Path) -> (PathBuf, PathBuf, PathBuf) {
    let is_ours = out.extension().is_some_and(|e| {
        let e = e.to_string_lossy().to_ascii_lowercase();
        e == "exr" || e == "png" || e == "json"
    });
    let stem = if is_ours {
        out.with_extension("")
    } else {
        out.to_path_buf()
    };
    let with = |ext: &str| {
        let mut s = OsString::from(stem.as_os_str());
        s.push(".");
        s.push(ext);
        PathBuf::from(s)
    };
    (with("exr"), with("png"), with("json"))
}

/// Writes a per-pixel map beside the image: `<out>.<name>.exr` (float32) and
/// `<out>.<name>.png` (the values in [0, 1] as 8 bits, no tone mapping or sRGB curve: a
/// visualisation, not a picture). Returns the two paths.
pub fn write_map(out: &Path, name: &str, map: &Image) -> Result<(PathBuf, PathBuf)> {
    let (exr_path, ..) = output_paths(out);
    let stem = exr_path.with_extension("");
    let with = |ext: &str| {
        let mut s = OsString::from(stem.as_os_str());
        s.push(format!(".{name}.{ext}"));
        PathBuf::from(s)
    };
    let (exr_map, png_map) = (with("exr"), with("png"));
    exr::write(&exr_map, map)?;
    let bytes: Vec<u8> = map
        .pixels
        .iter()
        .flat_map(|p| p.map(|c| (c.clamp(0.0, 1.0) * 255.0).round() as u8))
        .collect();
    png::write_rgb8(&png_map, map.width, map.height, &bytes)?;
    Ok((exr_map, png_map))
}

/// Writes `<out>.exr` (float32 linear RGB), `<out>.png` (tone-mapped at `exposure` stops) and
/// `<out>.json`, creating the parent folder, and returns the three paths.
pub fn write_all(
    out: &Path,
    image: &Image,
    record: &RenderRecord,
    exposure: f32,
) -> Result<(PathBuf, PathBuf, PathBuf)> {
    let (exr_path, png_path, json_path) = output_paths(out);
    if let Some(parent) = exr_path.parent().filter(|p| !p.as_os_str().is_empty()) {
        fs::create_dir_all(parent)
            .with_context(|| format!("creating the output folder {}", parent.display()))?;
    }
    exr::write(&exr_path, image)?;
    png::write(&png_path, image, exposure)?;
    record.write(&json_path)?;
    Ok((exr_path, png_path, json_path))
}
