//! The suite file (`irad bench suite <suite.toml>`): scenes, methods with fixed parameters and
//! budgets, the reference settings, and how each run is timed. Parsed with unknown fields
//! refused, every method setting checked by its table (`Registry::from_params`) before anything renders,
//! then expanded into a deterministic list of runs (scene, then method entry, then budget), the
//! order `--shard` splits. Format in docs/suites.md.

use std::collections::BTreeSet;
use std::ops::Range;
use std::path::{Path, PathBuf};

use serde::Deserialize;
use thiserror::Error;

use crate::methods::{Method, ParamError, Registry};

use super::generated::{self, Generated};
use crate::scene::hash::Fnv1a64;
use crate::scene::toml_arrays::exact_opt;
use crate::scene::MAX_RESOLUTION;
use crate::scene::{self, Scene, SceneError};

/// The largest time budget a suite may ask for: a day.
pub const MAX_TIME_MS: f64 = 86_400_000.0;

/// Seed of cached references unless the suite names one: far from the small seeds runs use,
/// so a run never shares its random numbers with its reference.
pub const REFERENCE_SEED: u32 = 0x9e37_79b9;

#[derive(Debug, Error)]
pub enum SuiteError {
    #[error("{file}: {message}")]
    File { file: String, message: String },
    #[error("{file}: {field} = {value}: {problem}")]
    Field {
        file: String,
        field: String,
        value: String,
        problem: String,
    },
    // `cause`, not `source`: the message already holds it, so `{:#}` does not repeat it.
    #[error("{file}: {field}: {cause}")]
    Param {
        file: String,
        field: String,
        cause: Box<ParamError>,
    },
    #[error("{file}: {field}: {cause}")]
    Scene {
        file: String,
        field: String,
        cause: Box<SceneError>,
    },
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct SuiteFile {
    name: String,
    #[serde(default)]
    description: String,
    width: Option<i64>,
    #[serde(default = "one")]
    seed: i64,
    #[serde(default = "one")]
    warmup: i64,
    #[serde(default = "three")]
    repeats: i64,
    #[serde(default = "four")]
    flicker_frames: i64,
    #[serde(default)]
    lead_in: i64,
    reference: toml::Table,
    #[serde(default)]
    scene: Vec<SceneEntry>,
    #[serde(default)]
    method: Vec<MethodEntry>,
}

fn one() -> i64 {
    1
}
fn three() -> i64 {
    3
}
fn four() -> i64 {
    4
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct SceneEntry {
    path: String,
    #[serde(default, deserialize_with = "exact_opt")]
    resolution: Option<[i64; 2]>,
    reference_spp: Option<i64>,
    /// The reference's max_depth for this scene (1: direct light, for a method that
    /// estimates only that).
    reference_max_depth: Option<i64>,
    /// Labels of the [[method]] entries this scene showcases (marked in the equal-time table).
    #[serde(default)]
    home: Vec<String>,
    /// For an animated scene: the frames its runs render and score, "A..B" (A included, B
    /// not); default every frame of its animation.
    frames: Option<String>,
    /// For a generated scene (`path = "generated:NAME"`): its light count, or a list of counts,
    /// one scene each (generated.rs).
    lights: Option<toml::Value>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct MethodEntry {
    method: String,
    label: Option<String>,
    scenes: Option<Vec<String>>,
    #[serde(default)]
    params: toml::Table,
    budgets: Vec<toml::Table>,
}

/// A loaded, checked suite.
#[derive(Debug)]
pub struct Suite {
    pub name: String,
    pub description: String,
    /// The suite file, for messages and records.
    pub file: String,
    /// FNV-1a 64 of the suite text and every scene's content hash: parts of one suite merge.
    pub hash: u64,
    /// The suite file's text (results record it, so a later run can name an edit).
    pub text: String,
    pub seed: u32,
    pub warmup: u32,
    pub repeats: u32,
    /// Renders with successive seeds whose flicker is measured (0: none).
    pub flicker_frames: u32,
    /// Frames a frame-time run of a method that carries state across frames renders, unscored,
    /// before each sequence's scored frames (so they start with the history a running
    /// application has), where the animation has them.
    pub lead_in: u32,
    pub scenes: Vec<SuiteScene>,
    pub entries: Vec<SuiteMethod>,
    /// Every run in suite order; `index` is the position here.
    pub runs: Vec<RunSpec>,
}

#[derive(Debug)]
pub struct SuiteScene {
    /// The scene with the suite's resolution applied.
    pub scene: Scene,
    /// The scene's path as the suite file writes it.
    pub path: String,
    /// The reference method (seed included) for this scene.
    pub reference: Method,
    /// Labels of the method entries whose home this scene is (the suite's `home`).
    pub home: Vec<String>,
    /// For an animated scene (`scene.animation` is Some): the frames its runs render and
    /// score (the suite's `frames`, or all); None for a still scene.
    pub frames: Option<Range<u32>>,
    /// The `[[scene]]` of the suite file it comes from (a generated family's members share
    /// one), for messages: `scene[2].home`.
    pub entry: usize,
    /// A member of a generated family (`path = "generated:NAME"`, `lights`): its generator and
    /// light count; None for a scene file.
    pub generated: Option<Generated>,
    /// Wall milliseconds loading the scene took (its files read, parsed and checked).
    pub load_ms: f64,
}

impl SuiteScene {
    /// The frame a frame-time budget is calibrated on: the middle of the scene's frames.
    pub fn calibration_frame(&self) -> Option<u32> {
        self.frames
            .as_ref()
            .map(|r| r.start + (r.end - r.start) / 2)
    }
}

#[derive(Debug)]
pub struct SuiteMethod {
    pub method: String,
    /// The series name in charts and tables (unique in the suite).
    pub label: String,
}

/// One run: a method at one budget on one scene.
#[derive(Clone, Debug)]
pub struct RunSpec {
    pub index: usize,
    pub scene: usize,
    pub entry: usize,
    /// The method and settings; its seed is the suite's base seed (repeat r adds r).
    pub method: Method,
    /// The budget's keys as written, `vpls=64 frames=4`.
    pub budget: String,
    /// A time budget (`time_ms`): GPU milliseconds the run's count (`Method::count_key`:
    /// frames, or the reference's spp) is calibrated to fill before it renders (calibrate.rs);
    /// `method` holds the default count until then.
    pub time_ms: Option<f64>,
    /// A frame-time budget (`frame_ms`), on an animated scene: GPU milliseconds per frame the
    /// count is calibrated to fill (on the scene's `calibration_frame`), then every frame of
    /// the scene's `frames` is rendered with it.
    pub frame_ms: Option<f64>,
    /// `<scene>/<label>/<budget>`, unique, stable across shards.
    pub id: String,
}

impl RunSpec {
    /// A file name for the run's images: the index, then the id with every character that is
    /// not `[A-Za-z0-9._=-]` replaced by `_`.
    pub fn file_stem(&self) -> String {
        // The index keeps stems unique where names differ only in characters file_safe
        // replaces ("a_b/c" and "a/b_c").
        format!("{:04}-{}", self.index, file_safe(&self.id))
    }
}

pub fn file_safe(s: &str) -> String {
    s.chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || "._=-".contains(c) {
                c
            } else {
                '_'
            }
        })
        .collect()
}

impl Suite {
    /// Loads the suite file at `path` and every scene it names; its methods are irad's.
    pub fn load(path: &Path) -> Result<Suite, SuiteError> {
        Suite::load_with(path, Registry::builtin())
    }

    /// `load` with the methods of `registry` (irad's and one of yours: `Registry::with`).
    /// Generated scenes (`path = "generated:NAME"`) are generated into, or found in,
    /// `generated::default_folder()` (out/generated).
    pub fn load_with(path: &Path, registry: &Registry) -> Result<Suite, SuiteError> {
        Suite::load_generating(path, registry, &generated::default_folder())
    }

    /// `load_with`, its generated scenes in the folder `generated`.
    pub fn load_generating(
        path: &Path,
        registry: &Registry,
        generated: &Path,
    ) -> Result<Suite, SuiteError> {
        let file = path.display().to_string();
        let text = std::fs::read_to_string(path).map_err(|e| SuiteError::File {
            file: file.clone(),
            message: format!("cannot read it: {e}"),
        })?;
        Suite::parse_generating(
            &file,
            &text,
            path.parent().unwrap_or(Path::new("")),
            registry,
            generated,
        )
    }

    /// Parses suite text; scene paths are relative to `base`; `file` names it in messages;
    /// its methods are irad's.
    pub fn parse(file: &str, text: &str, base: &Path) -> Result<Suite, SuiteError> {
        Suite::parse_with(file, text, base, Registry::builtin())
    }

    /// `parse` with the methods of `registry`; generated scenes in `generated::default_folder()`.
    pub fn parse_with(
        file: &str,
        text: &str,
        base: &Path,
        registry: &Registry,
    ) -> Result<Suite, SuiteError> {
        Suite::parse_generating(file, text, base, registry, &generated::default_folder())
    }

    /// `parse_with`, its generated scenes (`path = "generated:NAME"`) generated into, or
    /// found in, the folder `generated`.
    pub fn parse_generating(
        file: &str,
        text: &str,
        base: &Path,
        registry: &Registry,
        generated: &Path,
    ) -> Result<Suite, SuiteError> {
        let f: SuiteFile = toml::from_str(text).map_err(|e| SuiteError::File {
            file: file.into(),
            message: e.to_string().trim_end().to_string(),
        })?;
        check_name(file, &f.name)?;
        let counts = parse_counts(file, &f)?;
        let (reference_params, reference) = parse_reference(file, &f.reference)?;
        if f.scene.is_empty() {
            return Err(SuiteError::File {
                file: file.into(),
                message: "no [[scene]]: a suite needs at least one".into(),
            });
        }
        if f.method.is_empty() {
            return Err(SuiteError::File {
                file: file.into(),
                message: "no [[method]]: a suite needs at least one".into(),
            });
        }
        // The methods' names and settings first: loading the scenes can take minutes (a
        // generated hall is generated), and a misspelt method should not wait for it.
        for (i, m) in f.method.iter().enumerate() {
            parse_budgets(file, i, m, counts.seed, registry)?;
        }
        let scenes = parse_scenes(
            file,
            &f,
            (base, generated),
            &reference_params,
            &reference,
            registry,
        )?;
        check_reference_seeds(file, &scenes, &counts)?;
        let (entries, budgets) = parse_methods(file, &f.method, &scenes, counts.seed, registry)?;
        check_homes(file, &scenes, &entries)?;
        let runs = expand_runs(file, &scenes, &f.method, &entries, &budgets)?;
        Ok(Suite {
            name: f.name,
            description: f.description,
            file: file.into(),
            hash: suite_hash(text, &scenes),
            text: text.into(),
            seed: counts.seed,
            warmup: counts.warmup,
            repeats: counts.repeats,
            flicker_frames: counts.flicker_frames,
            lead_in: counts.lead_in,
            scenes,
            entries,
            runs,
        })
    }

    /// The runs of shard `index` of `count`: run i belongs to shard i mod count (round robin,
    /// so every shard gets a share of each scene and budget).
    pub fn shard(&self, shard: Shard) -> Vec<&RunSpec> {
        self.runs
            .iter()
            .filter(|r| r.index % shard.count == shard.index)
            .collect()
    }
}

/// A `SuiteError::Field`: `field = value` of `file` has `problem`.
fn field_error(file: &str, field: &str, value: String, problem: &str) -> SuiteError {
    SuiteError::Field {
        file: file.into(),
        field: field.into(),
        value,
        problem: problem.into(),
    }
}

/// A `SuiteError::Param`: `Method::from_params` refused the settings at `field`.
fn param_error(file: &str, field: String, source: ParamError) -> SuiteError {
    SuiteError::Param {
        file: file.into(),
        field,
        cause: Box::new(source),
    }
}

/// The suite's counts, checked.
struct Counts {
    seed: u32,
    warmup: u32,
    repeats: u32,
    flicker_frames: u32,
    lead_in: u32,
}

/// The method settings of one budget of entry `entry`, number `index`.
struct Budget {
    /// The method (seed set to the suite's).
    method: Method,
    /// The budget's label (`vpls=64 frames=4`, or `defaults`).
    text: String,
    time_ms: Option<f64>,
    frame_ms: Option<f64>,
    /// The field a fixed count is set at (`params.spp`, `budgets[1].frames`), if one is.
    count_field: Option<String>,
    index: usize,
}

/// Checks the suite's name: it names files and folders.
fn check_name(file: &str, name: &str) -> Result<(), SuiteError> {
    if name.trim().is_empty() || file_safe(name) != name || name.chars().all(|c| c == '.') {
        return Err(field_error(
            file,
            "name",
            format!("{name:?}"),
            "must use only letters, digits, '.', '_', '=' and '-', and not only dots",
        ));
    }
    Ok(())
}

/// Checks the seed, warm-up, repeats and flicker frames, and the suite's `width`.
fn parse_counts(file: &str, f: &SuiteFile) -> Result<Counts, SuiteError> {
    let count = |name: &str, v: i64, min: i64| {
        if v < min || v > u32::MAX as i64 {
            Err(field_error(
                file,
                name,
                v.to_string(),
                &format!("must be an integer >= {min}"),
            ))
        } else {
            Ok(v as u32)
        }
    };
    let seed = count("seed", f.seed, 0)?;
    let warmup = count("warmup", f.warmup, 0)?;
    let repeats = count("repeats", f.repeats, 1)?;
    let flicker_frames = count("flicker_frames", f.flicker_frames, 0)?;
    let lead_in = count("lead_in", f.lead_in, 0)?;
    if flicker_frames == 1 {
        return Err(field_error(
            file,
            "flicker_frames",
            "1".into(),
            "flicker needs 2 or more frames (0 turns it off)",
        ));
    }
    if let Some(w) = f.width {
        if !SIZES.contains(&w) {
            return Err(field_error(
                file,
                "width",
                w.to_string(),
                &format!("must be in 1..={MAX_RESOLUTION}"),
            ));
        }
    }
    Ok(Counts {
        seed,
        warmup,
        repeats,
        flicker_frames,
        lead_in,
    })
}

/// The scene files' limit on a width or height.
const SIZES: std::ops::RangeInclusive<i64> = 1..=MAX_RESOLUTION as i64;

/// Checks a scene's `resolution`, if it has one.
fn check_resolution(
    file: &str,
    name: &str,
    r: Option<[i64; 2]>,
) -> Result<Option<(u32, u32)>, SuiteError> {
    match r {
        None => Ok(None),
        Some([w, h]) if SIZES.contains(&w) && SIZES.contains(&h) => Ok(Some((w as u32, h as u32))),
        Some([w, h]) => Err(field_error(
            file,
            name,
            format!("[{w}, {h}]"),
            &format!("width and height must be in 1..={MAX_RESOLUTION}"),
        )),
    }
}

/// Reads `[reference]`: its parameters (the seed REFERENCE_SEED unless the suite pins one)
/// and the reference method they make.
fn parse_reference(file: &str, table: &toml::Table) -> Result<(toml::Table, Method), SuiteError> {
    // A suite may pin its references' seed; otherwise REFERENCE_SEED.
    let mut reference_params = table.clone();
    reference_params
        .entry("seed")
        .or_insert(toml::Value::Integer(REFERENCE_SEED as i64));
    let reference = Method::from_params("reference", &reference_params)
        .map_err(|e| param_error(file, "reference".into(), e))?;
    Ok((reference_params, reference))
}

/// Loads and checks every `[[scene]]` in order (a generated family's members in the order of
/// its `lights`): its file, resolution, name (unique), failure note and reference. Scene paths
/// are relative to `base`; generated scenes go in (or are found in) `generated_dir`.
fn parse_scenes(
    file: &str,
    f: &SuiteFile,
    (base, generated_dir): (&Path, &Path),
    reference_params: &toml::Table,
    reference: &Method,
    registry: &Registry,
) -> Result<Vec<SuiteScene>, SuiteError> {
    let mut scenes: Vec<SuiteScene> = Vec::new();
    let members = f
        .scene
        .iter()
        .enumerate()
        .map(|(i, entry)| {
            Ok(family(file, i, entry)?
                .into_iter()
                .map(move |m| (i, entry, m)))
        })
        .collect::<Result<Vec<_>, SuiteError>>()?;
    for (i, entry, member) in members.into_iter().flatten() {
        let (scene, load_ms) = load_scene(
            file,
            i,
            entry,
            member.as_ref(),
            (base, generated_dir),
            f.width,
        )?;
        let key = |name: &str| file_safe(name).to_lowercase();
        if let Some(prev) = scenes
            .iter()
            .find(|s| key(&s.scene.name) == key(&scene.name))
        {
            return Err(field_error(
                file,
                &format!("scene[{i}].path"),
                format!("{:?}", entry.path),
                &format!(
                    "a second scene named {:?} (scene names key charts and files, compared as file names, ignoring case)",
                    prev.scene.name
                ),
            ));
        }
        if let Some(note) = &scene.failure {
            if let Some(unknown) = note.methods.iter().find(|m| registry.get(m).is_err()) {
                return Err(field_error(
                    file,
                    &format!("scene[{i}] ({}) failure.methods", entry.path),
                    format!("{unknown:?}"),
                    &format!("not a method of this run ({})", registry.names().join(", ")),
                ));
            }
        }
        let reference = scene_reference(file, i, entry, reference_params, reference)?;
        let frames = scene_frames(file, i, entry, &scene)?;
        scenes.push(SuiteScene {
            scene,
            path: member
                .as_ref()
                .map_or_else(|| entry.path.clone(), Generated::path),
            reference,
            home: entry.home.clone(),
            frames,
            entry: i,
            generated: member,
            load_ms,
        });
    }
    Ok(scenes)
}

/// The scenes `[[scene]]` `i` stands for: itself (None), or a generated family's members, one
/// per count of its `lights`, each generated before the next is loaded. The generator and the
/// counts are checked here, before anything is generated.
fn family(file: &str, i: usize, entry: &SceneEntry) -> Result<Vec<Option<Generated>>, SuiteError> {
    let name = entry.path.strip_prefix(generated::PREFIX);
    let Some(name) = name else {
        return match &entry.lights {
            None => Ok(vec![None]),
            Some(v) => Err(field_error(
                file,
                &format!("scene[{i}].lights"),
                v.to_string(),
                &format!(
                    "only a generated scene takes a light count ({:?} is a scene file; a generated one is \
                     path = \"{}{}\")",
                    entry.path,
                    generated::PREFIX,
                    generated::GENERATORS[0].name
                ),
            )),
        };
    };
    let path_error = |problem: &str| {
        field_error(
            file,
            &format!("scene[{i}].path"),
            format!("{:?}", entry.path),
            problem,
        )
    };
    let g = generated::generator(name).map_err(|e| path_error(&e))?;
    let Some(lights) = &entry.lights else {
        return Err(path_error(&format!(
            "a generated scene needs `lights`: a light count or a list of them, 1 to {}",
            g.max_lights
        )));
    };
    let counts = generated::counts(lights, g.max_lights).map_err(|(at, value, problem)| {
        field_error(file, &format!("scene[{i}].lights{at}"), value, &problem)
    })?;
    Ok(counts
        .into_iter()
        .map(|lights| {
            Some(Generated {
                generator: g.name.into(),
                lights,
            })
        })
        .collect())
}

/// The frames of scene `i`: its `frames = "A..B"` (an animated scene's, within its
/// animation), or every frame of its animation; None for a still scene.
fn scene_frames(
    file: &str,
    i: usize,
    entry: &SceneEntry,
    scene: &Scene,
) -> Result<Option<Range<u32>>, SuiteError> {
    let field = format!("scene[{i}].frames");
    let Some(animation) = &scene.animation else {
        return match &entry.frames {
            None => Ok(None),
            Some(text) => Err(field_error(
                file,
                &field,
                format!("{text:?}"),
                &format!(
                    "{} is not animated: only an animated scene has frames",
                    entry.path
                ),
            )),
        };
    };
    let n = animation.frames;
    let Some(text) = &entry.frames else {
        return Ok(Some(0..n));
    };
    let parsed = text
        .split_once("..")
        .and_then(|(a, b)| Some((a.trim().parse::<u32>().ok()?, b.trim().parse::<u32>().ok()?)));
    match parsed {
        Some((a, b)) if a < b && b <= n => Ok(Some(a..b)),
        _ => Err(field_error(
            file,
            &field,
            format!("{text:?}"),
            &format!(
                "must be \"A..B\", frames A (included) to B (not), 0 <= A < B <= {n} (the animation's {n} frames)"
            ),
        )),
    }
}

/// Loads scene `i` (a file relative to `base`, the embedded Cornell box, or `member` of a
/// generated family, generated into `generated_dir` first when it is not there) at its own
/// resolution, or at the suite's `width` and the scene's aspect ratio; with the wall
/// milliseconds the load took (a generator's run left out).
fn load_scene(
    file: &str,
    i: usize,
    entry: &SceneEntry,
    member: Option<&Generated>,
    (base, generated_dir): (&Path, &Path),
    width: Option<i64>,
) -> Result<(Scene, f64), SuiteError> {
    let mut start = std::time::Instant::now();
    let mut scene = if let Some(m) = member {
        let g = generated::generator(&m.generator).map_err(|e| {
            field_error(
                file,
                &format!("scene[{i}].path"),
                format!("{:?}", entry.path),
                &e,
            )
        })?;
        let path = generated::scene_file(g, m.lights, generated_dir).map_err(|e| {
            field_error(
                file,
                &format!("scene[{i}].lights"),
                m.lights.to_string(),
                &format!("generating {}: {e}", entry.path),
            )
        })?;
        start = std::time::Instant::now();
        let mut scene = scene::load(&path).map_err(|source| SuiteError::Scene {
            file: file.into(),
            field: format!("scene[{i}].path = {:?}, lights = {}", entry.path, m.lights),
            cause: Box::new(source),
        })?;
        scene.name = m.scene_name();
        scene
    } else if let Some(name) = entry.path.strip_prefix("embedded:") {
        if name != "cornell-box" {
            return Err(field_error(
                file,
                &format!("scene[{i}].path"),
                format!("{:?}", entry.path),
                "the only embedded scene is embedded:cornell-box",
            ));
        }
        scene::default_scene()
    } else {
        scene::load(&base.join(&entry.path)).map_err(|source| SuiteError::Scene {
            file: file.into(),
            field: format!("scene[{i}].path = {:?}", entry.path),
            cause: Box::new(source),
        })?
    };
    let load_ms = start.elapsed().as_secs_f64() * 1e3;
    let own = check_resolution(file, &format!("scene[{i}].resolution"), entry.resolution)?;
    if let Some((w, h)) = own {
        scene.camera.width = w;
        scene.camera.height = h;
    } else if let Some(w) = width {
        // The scene's own aspect ratio, so the framing is the scene's.
        let cam = &mut scene.camera;
        let h = (w as f64 * cam.height as f64 / cam.width as f64)
            .round()
            .max(1.0);
        if h > f64::from(MAX_RESOLUTION) {
            return Err(field_error(
                file,
                "width",
                w.to_string(),
                &format!(
                    "gives {} ({}x{h} at its aspect ratio) a height over {MAX_RESOLUTION}",
                    entry.path, w
                ),
            ));
        }
        cam.width = w as u32;
        cam.height = h as u32;
    }
    Ok((scene, load_ms))
}

/// The reference of scene `i`: the suite's, with the scene's `reference_spp` and
/// `reference_max_depth` where it sets them.
fn scene_reference(
    file: &str,
    i: usize,
    entry: &SceneEntry,
    reference_params: &toml::Table,
    reference: &Method,
) -> Result<Method, SuiteError> {
    if entry.reference_spp.is_none() && entry.reference_max_depth.is_none() {
        return Ok(reference.clone());
    }
    let mut p = reference_params.clone();
    let mut fields = vec![];
    for (key, value) in [
        ("spp", entry.reference_spp),
        ("max_depth", entry.reference_max_depth),
    ] {
        if let Some(v) = value {
            p.insert(key.into(), toml::Value::Integer(v));
            fields.push(format!("scene[{i}].reference_{key}"));
        }
    }
    Method::from_params("reference", &p).map_err(|e| param_error(file, fields.join(", "), e))
}

/// FNV-1a 64 of the suite text, then of every scene's content hash in suite order.
fn suite_hash(text: &str, scenes: &[SuiteScene]) -> u64 {
    suite_hash_of(text, scenes.iter().map(|s| s.scene.content_hash))
}

/// `Suite::hash` of a suite text and its scenes' content hashes, in suite order.
pub fn suite_hash_of(text: &str, scene_hashes: impl IntoIterator<Item = u64>) -> u64 {
    let mut hash = Fnv1a64::default();
    hash.write(text.as_bytes());
    for h in scene_hashes {
        hash.write(&h.to_le_bytes());
    }
    hash.finish()
}

/// Checks that no scene's reference shares seeds with the runs.
fn check_reference_seeds(
    file: &str,
    scenes: &[SuiteScene],
    counts: &Counts,
) -> Result<(), SuiteError> {
    let seed = counts.seed;
    // A frame-time run's sequence r renders frame f with seed + r B + f, B the end of its
    // scene's frames (suite/sequence.rs).
    let frames = scenes
        .iter()
        .filter_map(|s| s.frames.as_ref().map(|r| u64::from(r.end)))
        .max()
        .unwrap_or(1);
    let renders = counts.warmup as u64 + counts.repeats.max(counts.flicker_frames) as u64 * frames;
    let run_seed = |s: u32| (s.wrapping_sub(seed) as u64) < renders;
    for s in scenes {
        // The reference is two halves, seeds r and r + 1 (references.rs).
        let i = s.entry;
        let r = s.reference.seed();
        if run_seed(r) || run_seed(r.wrapping_add(1)) {
            return Err(field_error(
                file,
                "reference.seed",
                r.to_string(),
                &format!(
                    "the reference of scene[{i}] would share random numbers with the runs, which use seeds {seed}..{} (seed + warm-up + repeats or flicker frames, times an animated scene's frames): pick a seed far from them",
                    seed as u64 + renders
                ),
            ));
        }
    }
    Ok(())
}

/// Checks every `[[method]]` in order (label, scenes, params) and makes its budgets' methods,
/// checked whatever scenes apply: the entries, and per entry its budgets.
fn parse_methods(
    file: &str,
    methods: &[MethodEntry],
    scenes: &[SuiteScene],
    seed: u32,
    registry: &Registry,
) -> Result<(Vec<SuiteMethod>, Vec<Vec<Budget>>), SuiteError> {
    let scene_names: BTreeSet<&str> = scenes.iter().map(|s| s.scene.name.as_str()).collect();
    let mut entries = Vec::new();
    let mut labels = BTreeSet::new();
    let mut budgets: Vec<Vec<Budget>> = Vec::new();
    for (i, m) in methods.iter().enumerate() {
        let label = m.label.clone().unwrap_or_else(|| m.method.clone());
        if label.is_empty() || file_safe(&label) != label {
            return Err(field_error(
                file,
                &format!("method[{i}].label"),
                format!("{label:?}"),
                "must be non-empty and use only letters, digits, '.', '_', '=' and '-'",
            ));
        }
        if !labels.insert(label.clone()) {
            return Err(field_error(
                file,
                &format!("method[{i}].label"),
                format!("{label:?}"),
                "used by an earlier [[method]]: give each a distinct label",
            ));
        }
        if let Some(names) = &m.scenes {
            if names.is_empty() {
                return Err(field_error(
                    file,
                    &format!("method[{i}].scenes"),
                    "[]".into(),
                    "names no scene: leave it out to run on every scene",
                ));
            }
            if let Some(unknown) = names.iter().find(|n| !scene_names.contains(n.as_str())) {
                return Err(field_error(
                    file,
                    &format!("method[{i}].scenes"),
                    format!("{unknown:?}"),
                    "not the name of a [[scene]] in this suite",
                ));
            }
        }
        if m.params.contains_key("seed") {
            return Err(field_error(
                file,
                &format!("method[{i}].params.seed"),
                m.params["seed"].to_string(),
                "the suite sets seeds (its `seed`, plus one per repeat)",
            ));
        }
        if m.budgets.is_empty() {
            return Err(field_error(
                file,
                &format!("method[{i}].budgets"),
                "[]".into(),
                "needs at least one budget ({} for the defaults)",
            ));
        }
        budgets.push(parse_budgets(file, i, m, seed, registry)?);
        entries.push(SuiteMethod {
            method: m.method.clone(),
            label,
        });
    }
    Ok((entries, budgets))
}

/// Makes the method of each budget of entry `i` (its params plus the budget's keys, the
/// suite's seed) and checks it: time budgets, overrides, duplicates.
fn parse_budgets(
    file: &str,
    i: usize,
    m: &MethodEntry,
    seed: u32,
    registry: &Registry,
) -> Result<Vec<Budget>, SuiteError> {
    let field =
        |field: &str, value: String, problem: &str| field_error(file, field, value, problem);
    let mut methods: Vec<Budget> = Vec::new();
    for (b, budget) in m.budgets.iter().enumerate() {
        let mut params = m.params.clone();
        if let Some(v) = m.params.get("time_ms") {
            return Err(field(
                &format!("method[{i}].params.time_ms"),
                v.to_string(),
                "a time budget belongs in budgets, one per budget",
            ));
        }
        if let Some(v) = m.params.get("frame_ms") {
            return Err(field(
                &format!("method[{i}].params.frame_ms"),
                v.to_string(),
                "a frame-time budget belongs in budgets, one per budget",
            ));
        }
        let ms = |key: &str| match budget.get(key) {
            None => Ok(None),
            Some(v) => match v.as_float().or(v.as_integer().map(|i| i as f64)) {
                Some(t) if t > 0.0 && t <= MAX_TIME_MS => Ok(Some(t)),
                _ => Err(field(
                    &format!("method[{i}].budgets[{b}].{key}"),
                    v.to_string(),
                    &format!("must be GPU milliseconds, a number in (0, {MAX_TIME_MS}]"),
                )),
            },
        };
        let time_ms = ms("time_ms")?;
        let frame_ms = ms("frame_ms")?;
        if let (Some(_), Some(f)) = (time_ms, frame_ms) {
            return Err(field(
                &format!("method[{i}].budgets[{b}].frame_ms"),
                f.to_string(),
                "a budget is a time (time_ms, a still scene's render) or a frame time (frame_ms, \
                 each frame of an animated scene), not both",
            ));
        }
        for (k, v) in budget
            .iter()
            .filter(|(k, _)| *k != "time_ms" && *k != "frame_ms")
        {
            if k == "seed" || params.contains_key(k) {
                return Err(field(
                    &format!("method[{i}].budgets[{b}].{k}"),
                    v.to_string(),
                    "also set in params (or a seed): a budget adds keys, it does not override",
                ));
            }
            params.insert(k.clone(), v.clone());
        }
        params.insert("seed".into(), toml::Value::Integer(seed as i64));
        let method = registry
            .from_params(&m.method, &params)
            .map_err(|e| param_error(file, format!("method[{i}].budgets[{b}]"), e))?;
        let count_field = params.get(method.count_key()).map(|_| {
            let place = match m.params.contains_key(method.count_key()) {
                true => "params".to_string(),
                false => format!("budgets[{b}]"),
            };
            format!("method[{i}].{place}.{}", method.count_key())
        });
        if let (Some(v), Some(at)) = (params.get(method.count_key()), &count_field) {
            let kind = match (time_ms, frame_ms) {
                (Some(_), _) => Some("time_ms"),
                (_, Some(_)) => Some("frame_ms"),
                _ => None,
            };
            if let Some(kind) = kind {
                return Err(field(
                    at,
                    v.to_string(),
                    &format!(
                        "a {kind} budget calibrates {} itself: leave it out",
                        method.count_key()
                    ),
                ));
            }
        }
        let text = budget
            .iter()
            .map(|(k, v)| format!("{k}={}", plain(v)))
            .collect::<Vec<_>>()
            .join(" ");
        let text = if text.is_empty() {
            "defaults".into()
        } else {
            text
        };
        if let Some(same) = methods
            .iter()
            .find(|o| o.method == method && o.time_ms == time_ms && o.frame_ms == frame_ms)
        {
            return Err(field(
                &format!("method[{i}].budgets[{b}]"),
                format!("{{ {text} }}"),
                &format!("the same settings as budget {{ {} }}", same.text),
            ));
        }
        methods.push(Budget {
            method,
            text,
            time_ms,
            frame_ms,
            count_field,
            index: b,
        });
    }
    Ok(methods)
}

/// Checks that every scene's `home` names a method entry's label.
fn check_homes(
    file: &str,
    scenes: &[SuiteScene],
    entries: &[SuiteMethod],
) -> Result<(), SuiteError> {
    for s in scenes {
        let i = s.entry;
        if let Some(unknown) = s
            .home
            .iter()
            .find(|h| !entries.iter().any(|e| e.label == **h))
        {
            return Err(field_error(
                file,
                &format!("scene[{i}].home"),
                format!("{unknown:?}"),
                "not the label of a [[method]] in this suite",
            ));
        }
    }
    Ok(())
}

/// Expands the suite into its runs: per scene, per method entry that applies to it, per
/// budget; `index` is the position in this list. An animated scene takes only frame-time
/// budgets and a still scene none (`check_budget_fits`).
fn expand_runs(
    file: &str,
    scenes: &[SuiteScene],
    methods: &[MethodEntry],
    entries: &[SuiteMethod],
    budgets: &[Vec<Budget>],
) -> Result<Vec<RunSpec>, SuiteError> {
    let mut runs = Vec::new();
    for (s, suite_scene) in scenes.iter().enumerate() {
        for (e, m) in methods.iter().enumerate() {
            let applies = m
                .scenes
                .as_ref()
                .is_none_or(|names| names.contains(&suite_scene.scene.name));
            if !applies {
                continue;
            }
            for budget in &budgets[e] {
                check_budget_fits(file, suite_scene, e, budget)?;
                let id = format!(
                    "{}/{}/{}",
                    suite_scene.scene.name, entries[e].label, budget.text
                );
                runs.push(RunSpec {
                    index: runs.len(),
                    scene: s,
                    entry: e,
                    method: budget.method.clone(),
                    budget: budget.text.clone(),
                    time_ms: budget.time_ms,
                    frame_ms: budget.frame_ms,
                    id,
                });
            }
        }
    }
    Ok(runs)
}

/// Refuses budget `budget` of method entry `e` on `scene` where they do not fit: an
/// animated scene is timed per frame, so it takes only `frame_ms` budgets (a time_ms budget
/// or a fixed count would time one still render of an animation); a still scene has no
/// frames to time. Names the budget's field.
fn check_budget_fits(
    file: &str,
    scene: &SuiteScene,
    e: usize,
    budget: &Budget,
) -> Result<(), SuiteError> {
    let b = budget.index;
    // The suite file's [[scene]] (a generated family's members share one).
    let s = scene.entry;
    let name = &scene.scene.name;
    match (&scene.scene.animation, budget.frame_ms) {
        (Some(animation), None) => {
            let (field, value) = match (budget.time_ms, &budget.count_field) {
                (Some(t), _) => (format!("method[{e}].budgets[{b}].time_ms"), t.to_string()),
                (None, Some(at)) => (
                    at.clone(),
                    budget
                        .method
                        .parameters()
                        .get(budget.method.count_key())
                        .map_or("?".into(), |v| v.to_string()),
                ),
                (None, None) => (
                    format!("method[{e}].budgets[{b}]"),
                    format!("{{ {} }}", budget.text),
                ),
            };
            Err(field_error(
                file,
                &field,
                value,
                &format!(
                    "scene[{s}] ({name}) is animated ({} frames): its runs are timed per frame, so \
                     each budget on it is a frame time, {{ frame_ms = X }}, which calibrates {} \
                     (limit the method to other scenes with `scenes = [...]`)",
                    animation.frames,
                    budget.method.count_key()
                ),
            ))
        }
        (None, Some(f)) => Err(field_error(
            file,
            &format!("method[{e}].budgets[{b}].frame_ms"),
            f.to_string(),
            &format!(
                "scene[{s}] ({name}) is not animated: a frame-time budget is for an animated \
                 scene (time_ms times a still render; limit the method to animated scenes with \
                 `scenes = [...]`)"
            ),
        )),
        _ => Ok(()),
    }
}

/// `--shard i/n`: part i (0-based) of n.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct Shard {
    pub index: usize,
    pub count: usize,
}

impl Shard {
    pub const WHOLE: Shard = Shard { index: 0, count: 1 };
}

impl std::str::FromStr for Shard {
    type Err = String;
    fn from_str(s: &str) -> Result<Shard, String> {
        let bad = || format!("`{s}`: expected I/N with 0 <= I < N (0-based, e.g. 0/4 .. 3/4)");
        let (i, n) = s.split_once('/').ok_or_else(bad)?;
        let index: usize = i.trim().parse().map_err(|_| bad())?;
        let count: usize = n.trim().parse().map_err(|_| bad())?;
        if count == 0 || index >= count {
            return Err(bad());
        }
        Ok(Shard { index, count })
    }
}

impl std::fmt::Display for Shard {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}/{}", self.index, self.count)
    }
}

/// A TOML value as a budget label shows it: strings unquoted.
fn plain(v: &toml::Value) -> String {
    match v {
        toml::Value::String(s) => s.clone(),
        other => other.to_string(),
    }
}

/// The built-in quick suite (`--quick`): scenes/suites/quick.toml of the source tree irad was
/// built from, since it names scenes on disk.
pub fn quick_suite_path() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/suites/quick.toml")
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A suite of `scenes` (TOML `[[scene]]` tables) with one path-tracer method.
    fn suite(scenes: &str) -> String {
        format!(
            "name = \"t\"\n[reference]\nspp = 4\n{scenes}\n[[method]]\nmethod = \"reference\"\nbudgets = [{{ spp = 1 }}]\n"
        )
    }

    fn error(scenes: &str) -> String {
        let dir = std::env::temp_dir().join("irad-suite-file-tests-unused");
        Suite::parse_generating(
            "s.toml",
            &suite(scenes),
            Path::new("."),
            Registry::builtin(),
            &dir,
        )
        .map(|_| ())
        .unwrap_err()
        .to_string()
    }

    /// A generated scene's `path` and `lights` are checked before anything is generated, each
    /// error naming the file, the field (the `[[scene]]`'s index in the file) and the value.
    #[test]
    fn generated_scenes_refuse_bad_paths_and_counts() {
        let cornell = "[[scene]]\npath = \"embedded:cornell-box\"\n";
        for (scenes, expected) in [
            (
                format!("{cornell}lights = 16\n"),
                "s.toml: scene[0].lights = 16: only a generated scene takes a light count",
            ),
            (
                format!("{cornell}[[scene]]\npath = \"generated:hall\"\nlights = 16\n"),
                "s.toml: scene[1].path = \"generated:hall\": no such generator: the generators \
                 are generated:many-lights",
            ),
            (
                "[[scene]]\npath = \"generated:many-lights\"\n".to_string(),
                "s.toml: scene[0].path = \"generated:many-lights\": a generated scene needs \
                 `lights`",
            ),
            (
                "[[scene]]\npath = \"generated:many-lights\"\nlights = [16, 0]\n".to_string(),
                "s.toml: scene[0].lights[1] = 0: a light count is an integer from 1 to 1048576",
            ),
            (
                "[[scene]]\npath = \"generated:many-lights\"\nlights = 1048577\n".to_string(),
                "s.toml: scene[0].lights = 1048577: a light count is an integer from 1 to",
            ),
            (
                "[[scene]]\npath = \"generated:many-lights\"\nlights = []\n".to_string(),
                "s.toml: scene[0].lights = []: names no count",
            ),
            (
                "[[scene]]\npath = \"generated:many-lights\"\nlights = [16, 32, 16]\n".to_string(),
                "s.toml: scene[0].lights[2] = 16: listed twice",
            ),
            (
                "[[scene]]\npath = \"generated:many-lights\"\nlights = \"16\"\n".to_string(),
                "s.toml: scene[0].lights = \"16\": a light count is an integer",
            ),
        ] {
            let e = error(&scenes);
            assert!(e.starts_with(expected), "{e}\nwanted: {expected}");
        }
    }

    /// `lights = [4, 16]` is two scenes, generated into the folder given and loaded from
    /// there, each named by its count and carrying it; a second load finds them there. Errors
    /// about a later `[[scene]]` name its index in the file, not in the expanded list. Skipped
    /// without python3 (outside CI).
    #[test]
    fn a_generated_family_is_one_scene_per_count() {
        if std::process::Command::new("python3")
            .arg("--version")
            .output()
            .is_err()
        {
            let ci = std::env::var("CI").is_ok_and(|v| !v.is_empty() && v != "false" && v != "0");
            assert!(!ci, "python3 is needed under CI");
            eprintln!("note: no python3; skipping");
            return;
        }
        let dir = std::env::temp_dir().join(format!("irad-suite-family-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        let text = suite(
            "[[scene]]\npath = \"generated:many-lights\"\nlights = [4, 16]\nreference_max_depth = 1\n\
             [[scene]]\npath = \"embedded:cornell-box\"\n",
        );
        let parse = |text: &str| {
            Suite::parse_generating("s.toml", text, Path::new("."), Registry::builtin(), &dir)
        };
        // A misspelt method is refused before any hall is generated.
        let misspelt = text.replace("method = \"reference\"", "method = \"refrence\"");
        assert_ne!(misspelt, text);
        let e = parse(&misspelt).map(|_| ()).unwrap_err().to_string();
        assert!(e.contains("refrence"), "{e}");
        assert!(!dir.exists(), "generated before the methods were checked");
        let s = parse(&text).unwrap_or_else(|e| panic!("{e}"));
        let names: Vec<&str> = s.scenes.iter().map(|s| s.scene.name.as_str()).collect();
        assert_eq!(names, ["many-lights-4", "many-lights-16", "cornell-box"]);
        assert_eq!(s.runs.len(), 3);
        assert_eq!(s.runs[1].id, "many-lights-16/reference/spp=1");
        for (scene, lights) in s.scenes[..2].iter().zip([4, 16]) {
            let g = scene.generated.as_ref().unwrap();
            assert_eq!((g.generator.as_str(), g.lights), ("many-lights", lights));
            assert_eq!(scene.path, format!("generated:many-lights lights={lights}"));
            assert_eq!(scene.entry, 0);
            assert_eq!(scene.reference.parameters()["max_depth"], 1);
            let emissive = scene
                .scene
                .triangles
                .iter()
                .filter(|t| scene.scene.materials[t.material as usize].is_emissive())
                .count();
            assert_eq!(emissive, 2 * lights as usize);
            assert!(scene.scene.source.as_ref().unwrap().starts_with(&dir));
        }
        assert_eq!(
            (s.scenes[2].entry, s.scenes[2].generated.as_ref()),
            (1, None)
        );
        // Found again, not generated again: the same folders, the same contents.
        let folders = || {
            let mut v: Vec<_> = std::fs::read_dir(&dir)
                .unwrap()
                .map(|e| e.unwrap().file_name())
                .collect();
            v.sort();
            v
        };
        let before = folders();
        assert_eq!(before.len(), 2, "{before:?}");
        let again = parse(&text).unwrap();
        assert_eq!(again.hash, s.hash);
        assert_eq!(folders(), before);
        let e = parse(&text.replace(
            "path = \"embedded:cornell-box\"\n",
            "path = \"embedded:cornell-box\"\nhome = [\"ir\"]\n",
        ))
        .unwrap_err()
        .to_string();
        assert!(e.starts_with("s.toml: scene[1].home = \"ir\""), "{e}");
        let _ = std::fs::remove_dir_all(&dir);
    }
}
