//! The JSON record beside every render (docs/DESIGN.md "Outputs"): what was rendered, how, on what,
//! how long each pass took and, when a reference was given, how far from it. Also where the
//! outputs of `-o <out>` go, and writing them as one set.

use std::collections::BTreeMap;
use std::ffi::OsString;
use std::fs;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

use anyhow::{bail, ensure, Context, Result};
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
    /// The scene file's absolute path (none for the built-in scene), so a record found later
    /// names the very file whatever folder it was rendered from.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub scene_path: Option<String>,
    /// Content hash of the scene and its assets, 16 hex digits.
    pub scene_hash: String,
    /// [width, height] in pixels.
    pub resolution: [u32; 2],
    pub seed: u64,
    /// The animation frame shown (an animated scene's; docs/DESIGN.md "Animation").
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub frame: Option<u32>,
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
    /// Error against the reference, when one was given...
    #[serde(default)]
    pub metrics: Option<Metrics>,
    /// ...and that reference: the EXR's absolute path.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub reference: Option<String>,
    #[serde(default)]
    pub warnings: Vec<String>,
    /// Method-specific figures (bir: fractions of kept VPLs per side, rays per kept VPL).
    #[serde(default)]
    pub stats: BTreeMap<String, f64>,
    /// The files of this render beside this JSON (EXR, PNG, maps): a map left by an earlier
    /// render under the same `-o` is not among them.
    #[serde(default)]
    pub files: Vec<String>,
    pub irad_version: String,
    /// The commit irad was built from, "-dirty" appended where its sources differed from it
    /// (build.rs; "unknown" outside a git checkout): timings move between commits.
    #[serde(default)]
    pub git_commit: String,
    /// What getting the scene to the device cost: reading and parsing its files, the BVH
    /// builds and the whole upload, in wall milliseconds (absent in records written before).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub load: Option<LoadTimes>,
}

/// Wall milliseconds of a scene's way to the device (`RenderRecord::load`).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct LoadTimes {
    /// Reading, decompressing, parsing and checking the scene's files (0 for a scene built
    /// in code).
    pub parse_ms: f64,
    /// The triangle BVH's build (obvhs).
    pub triangle_bvh_ms: f64,
    /// The light BVH's build.
    pub light_bvh_ms: f64,
    /// The whole upload: both builds, the shading data and tables, and the transfers.
    pub upload_ms: f64,
}

/// This build's commit (build.rs).
pub const GIT_COMMIT: &str = env!("IRAD_GIT_COMMIT");

/// `path` made absolute (the current folder joined where it is relative; symbolic links kept),
/// as records write the files they name.
pub fn absolute(path: &Path) -> String {
    std::path::absolute(path)
        .unwrap_or_else(|_| path.to_path_buf())
        .display()
        .to_string()
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

/// The stem of `-o <out>`'s files. A folder (an existing one, or a path ending in `/`, `.` or
/// `..`) gets the stem `<out>/render`, so its files are named, not hidden (`-o out/` would
/// otherwise give `out/.exr`); otherwise `out`, less a final `.exr`, `.png` or `.json` (so
/// `-o out/cornell.png` does not give `out/cornell.png.png`; any other dot in the name stays).
pub fn output_stem(out: &Path) -> PathBuf {
    if names_a_folder(out) {
        return out.join(FOLDER_STEM);
    }
    let is_ours = out.extension().is_some_and(|e| {
        let e = e.to_string_lossy().to_ascii_lowercase();
        e == "exr" || e == "png" || e == "json"
    });
    if is_ours {
        out.with_extension("")
    } else {
        out.to_path_buf()
    }
}

/// The file stem a folder given as `-o` gets.
pub const FOLDER_STEM: &str = "render";

/// `out` is a folder: an existing one, or written as one (`dir/`, `.`, `..`, `dir/.`).
fn names_a_folder(out: &Path) -> bool {
    let text = out.to_string_lossy();
    let written_as_folder = text.is_empty()
        || text.ends_with(std::path::is_separator)
        || Path::new(text.rsplit(std::path::is_separator).next().unwrap_or(""))
            .file_name()
            .is_none();
    written_as_folder || out.is_dir()
}

/// The EXR, PNG and JSON paths for `-o <out>`: the extensions appended to `output_stem(out)`
/// (`out/cornell` gives `out/cornell.exr`, `out/cornell.png`, `out/cornell.json`).
pub fn output_paths(out: &Path) -> (PathBuf, PathBuf, PathBuf) {
    let stem = output_stem(out);
    (
        with_suffix(&stem, ".exr"),
        with_suffix(&stem, ".png"),
        with_suffix(&stem, ".json"),
    )
}

/// A per-pixel map's EXR and PNG paths: `<stem>.<name>.exr` and `<stem>.<name>.png`.
pub fn map_paths(out: &Path, name: &str) -> (PathBuf, PathBuf) {
    let stem = output_stem(out);
    (
        with_suffix(&stem, &format!(".{name}.exr")),
        with_suffix(&stem, &format!(".{name}.png")),
    )
}

fn with_suffix(stem: &Path, suffix: &str) -> PathBuf {
    let mut s = OsString::from(stem.as_os_str());
    s.push(suffix);
    PathBuf::from(s)
}

/// The files one render writes.
#[derive(Clone, Debug, PartialEq)]
pub struct OutputFiles {
    pub exr: PathBuf,
    pub png: PathBuf,
    pub json: PathBuf,
    /// Each map's EXR and PNG, in the order the method gave them.
    pub maps: Vec<(PathBuf, PathBuf)>,
}

impl OutputFiles {
    pub fn new(out: &Path, map_names: &[&str]) -> OutputFiles {
        let (exr, png, json) = output_paths(out);
        OutputFiles {
            exr,
            png,
            json,
            maps: map_names.iter().map(|n| map_paths(out, n)).collect(),
        }
    }

    /// Every file, the JSON last.
    pub fn all(&self) -> Vec<&Path> {
        let mut all = vec![self.exr.as_path(), self.png.as_path()];
        for (e, p) in &self.maps {
            all.extend([e.as_path(), p.as_path()]);
        }
        all.push(&self.json);
        all
    }

    /// The folder they are written in.
    pub fn folder(&self) -> PathBuf {
        match self.json.parent() {
            Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
            _ => PathBuf::from("."),
        }
    }

    /// The file names beside the JSON that belong to it (what `RenderRecord::files` lists).
    pub fn names(&self) -> Vec<String> {
        self.all()
            .iter()
            .filter(|p| **p != self.json)
            .map(|p| {
                p.file_name()
                    .map(|n| n.to_string_lossy().into_owned())
                    .unwrap_or_default()
            })
            .collect()
    }
}

/// Checks, before any work, that the outputs of `-o <out>` can be written: their folder
/// exists or can be created, a file can be created in it, and no folder sits where one of
/// the EXR, PNG and JSON goes. Creates the folder.
pub fn check_writable(out: &Path) -> Result<OutputFiles> {
    let files = OutputFiles::new(out, &[]);
    prepare_folder(&files)?;
    let folder = files.folder();
    let probe = temp_name(&folder.join(".irad-probe"));
    fs::OpenOptions::new()
        .write(true)
        .create_new(true)
        .open(&probe)
        .with_context(|| {
            format!(
                "the output folder {} is not writable (creating {})",
                folder.display(),
                probe.display()
            )
        })?;
    fs::remove_file(&probe).with_context(|| format!("removing {}", probe.display()))?;
    Ok(files)
}

/// Creates the outputs' folder and checks that no output name is taken by a folder (the
/// rename would fail halfway through the set).
fn prepare_folder(files: &OutputFiles) -> Result<()> {
    let folder = files.folder();
    fs::create_dir_all(&folder)
        .with_context(|| format!("creating the output folder {}", folder.display()))?;
    for path in files.all() {
        if path.is_dir() {
            bail!(
                "{} is a folder, so the render cannot be written there: choose another -o",
                path.display()
            );
        }
    }
    Ok(())
}

/// A temporary name beside `path`, unique to this process and call: `.<name>.<pid>-<n>.tmp`.
fn temp_name(path: &Path) -> PathBuf {
    static NEXT: AtomicU64 = AtomicU64::new(0);
    let n = NEXT.fetch_add(1, Ordering::Relaxed);
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    path.with_file_name(format!(".{name}.{}-{n}.tmp", std::process::id()))
}

/// Files written under temporary names, renamed into place by `commit`; dropped before that,
/// their temporary files are removed, so a failed or interrupted write leaves the previous
/// files as they were and no partial file under an output's name.
#[derive(Default)]
struct Pending {
    /// (temporary, final) names, in the order they are renamed.
    files: Vec<(PathBuf, PathBuf)>,
}

impl Pending {
    fn write(&mut self, path: &Path, write: impl FnOnce(&Path) -> Result<()>) -> Result<()> {
        let tmp = temp_name(path);
        // Recorded first, so the drop removes what a failed write left.
        self.files.push((tmp.clone(), path.to_path_buf()));
        write(&tmp).with_context(|| format!("writing {}", path.display()))
    }

    /// Renames every file into place, in order, while holding the folder's lock: two renders
    /// writing the same names take turns, so the set left is one render's whole set.
    fn commit(mut self, files: &OutputFiles) -> Result<()> {
        let _lock = crate::lock::FolderLock::wait(&files.folder())?;
        // Checked again under the lock: a folder put in an output's place since the start
        // would fail its rename after the others had replaced the previous set.
        prepare_folder(files)?;
        let files = std::mem::take(&mut self.files);
        for (i, (tmp, path)) in files.iter().enumerate() {
            if let Err(e) = fs::rename(tmp, path) {
                // The drop removes the temporary files not renamed yet.
                self.files = files[i..].to_vec();
                return Err(e)
                    .with_context(|| format!("renaming {} to {}", tmp.display(), path.display()));
            }
        }
        Ok(())
    }
}

impl Drop for Pending {
    fn drop(&mut self) {
        for (tmp, _) in &self.files {
            let _ = fs::remove_file(tmp);
        }
    }
}

/// Writes a render's files as one set: `<out>.exr` (float32 linear RGB), `<out>.png` (tone
/// mapped at `exposure` stops), each map's `<out>.<name>.exr` and `.png` (the values in
/// [0, 1] as 8 bits, no tone mapping or sRGB curve: a visualisation, not a picture) and
/// `<out>.json`, creating the folder. Every file is written under a temporary name first, then
/// all are renamed into place, the JSON last: a failure (a full disk, a bad exposure) leaves
/// the previous set as it was, and a finished JSON means its images are in place. The record
/// is written as given; its `files` should be `OutputFiles::names`.
pub fn write_all(
    out: &Path,
    image: &Image,
    record: &RenderRecord,
    exposure: f32,
    maps: &[(String, Image)],
) -> Result<OutputFiles> {
    ensure!(
        exposure.is_finite(),
        "exposure must be a finite number of stops, got {exposure}"
    );
    let names: Vec<&str> = maps.iter().map(|(n, _)| n.as_str()).collect();
    let files = OutputFiles::new(out, &names);
    prepare_folder(&files)?;
    let mut pending = Pending::default();
    pending.write(&files.exr, |p| exr::write(p, image))?;
    pending.write(&files.png, |p| png::write(p, image, exposure))?;
    for ((_, map), (exr_map, png_map)) in maps.iter().zip(&files.maps) {
        pending.write(exr_map, |p| exr::write(p, map))?;
        let bytes: Vec<u8> = map
            .pixels
            .iter()
            .flat_map(|p| p.map(|c| (c.clamp(0.0, 1.0) * 255.0).round() as u8))
            .collect();
        pending.write(png_map, |p| {
            png::write_rgb8(p, map.width, map.height, &bytes)
        })?;
    }
    pending.write(&files.json, |p| record.write(p))?;
    pending.commit(&files)?;
    Ok(files)
}
