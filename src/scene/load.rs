//! From a scene file to a checked `Scene`: reads every referenced file (from disk, or from the
//! texts embedded in the binary for the default Cornell box), merges the meshes' triangles and
//! materials, drops degenerate triangles, and refuses scenes with no triangle or no light.

use std::path::{Path, PathBuf};

use glam::Vec3;

use super::animation::Animation;
use super::hash::Fnv1a64;
use super::sky::MovingSun;
use super::{camera, coincident, environment, failure, file, lights, luminaire, obj, power};
use super::{Environment, Material, Scene, SceneError, Triangle};

/// A triangle whose area is at most this times the square of its own longest edge is
/// degenerate (collinear or repeated corners, to f32 rounding) and dropped with a warning. Each
/// triangle is judged by its own size, so a small triangle beside a huge one is kept.
pub const DEGENERATE_AREA: f64 = 1e-12;

/// Loads the scene file at `path`; files it names are relative to its folder.
pub fn load(path: &Path) -> Result<Scene, SceneError> {
    load_with_camera(path, None)
}

/// `load`, seen through a glTF scene's `cameras[n]` for `camera` = Some(n) (an error for any
/// other format: only glTF files hold several cameras).
pub fn load_with_camera(path: &Path, camera: Option<usize>) -> Result<Scene, SceneError> {
    let start = std::time::Instant::now();
    let mut scene = load_file(path, camera)?;
    scene.load_ms = start.elapsed().as_secs_f64() * 1e3;
    Ok(scene)
}

/// The scene file's name for messages and its bytes: every format's first step.
pub(crate) fn read_scene_file(path: &Path) -> Result<(String, Vec<u8>), SceneError> {
    let file = path.display().to_string();
    let bytes = std::fs::read(path).map_err(|error| SceneError::Read {
        path: file.clone(),
        referenced_by: "the scene file".into(),
        error,
    })?;
    Ok((file, bytes))
}

fn load_file(path: &Path, camera: Option<usize>) -> Result<Scene, SceneError> {
    if let (Some(n), false) = (camera, super::gltf::is_gltf(path)) {
        return Err(SceneError::Invalid {
            file: path.display().to_string(),
            field: "--camera".into(),
            value: n.to_string(),
            problem: "picks a glTF scene's camera; this is not a .gltf or .glb file".into(),
        });
    }
    if super::mitsuba::is_mitsuba(path) {
        let mut scene = super::mitsuba::load(path)?;
        scene.name = scene_name(path);
        log_warnings(&scene);
        return Ok(scene);
    }
    if super::gltf::is_gltf(path) {
        let mut scene = super::gltf::load_with_camera(path, camera)?;
        scene.name = scene_name(path);
        log_warnings(&scene);
        return Ok(scene);
    }
    let (display, bytes) = read_scene_file(path)?;
    let text = String::from_utf8(bytes).map_err(|e| SceneError::File {
        file: display.clone(),
        message: format!("not UTF-8 text (TOML must be): {e}"),
    })?;
    let base = path.parent().unwrap_or(Path::new(""));
    let mut scene = build(&display, &text, &Files::Disk(base))?;
    scene.name = scene_name(path);
    scene.source = Some(path.to_path_buf());
    log_warnings(&scene);
    Ok(scene)
}

/// Loads a scene from TOML text; files it names are relative to `base_dir`. `name` names the
/// text in messages and becomes `Scene::name`; `Scene::source` is None.
pub fn load_str(toml_text: &str, base_dir: &Path, name: &str) -> Result<Scene, SceneError> {
    let mut scene = build(name, toml_text, &Files::Disk(base_dir))?;
    scene.name = name.to_string();
    log_warnings(&scene);
    Ok(scene)
}

/// A loaded scene's warnings, each through the `log` facade (they stay in `Scene::warnings`).
fn log_warnings(scene: &Scene) {
    for w in &scene.warnings {
        log::warn!("{w}");
    }
}

const CORNELL_TOML: &str = include_str!("../../scenes/cornell-box/scene.toml");
const CORNELL_OBJ: &str = include_str!("../../scenes/cornell-box/cornell-box.obj");
const CORNELL_MTL: &str = include_str!("../../scenes/cornell-box/cornell-box.mtl");

/// The Cornell box of scenes/cornell-box/, built from copies of its files embedded in the
/// binary (it needs no file at run time). Its content hash is that of the same files on disk.
pub fn default_scene() -> Scene {
    let files = Files::Embedded {
        label: "(embedded) scenes/cornell-box/",
        files: &[
            ("cornell-box.obj", CORNELL_OBJ),
            ("cornell-box.mtl", CORNELL_MTL),
        ],
    };
    let mut scene = build(
        "(embedded) scenes/cornell-box/scene.toml",
        CORNELL_TOML,
        &files,
    )
    .expect("the embedded Cornell box loads (tested)");
    scene.name = "cornell-box".into();
    scene
}

/// "cornell-box" for scenes/cornell-box/scene.toml, else the file's stem.
fn scene_name(path: &Path) -> String {
    let stem = path.file_stem().map(|s| s.to_string_lossy().into_owned());
    match stem.as_deref() {
        Some("scene") | None => path
            .canonicalize()
            .ok()
            .as_deref()
            .unwrap_or(path)
            .parent()
            .and_then(|p| p.file_name())
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_else(|| "scene".into()),
        Some(s) => s.to_string(),
    }
}

/// Where the files a scene references come from.
enum Files<'a> {
    /// Relative to this folder on disk.
    Disk(&'a Path),
    /// Texts embedded in the binary, by relative path; `label` prefixes their names.
    Embedded {
        label: &'static str,
        files: &'a [(&'static str, &'static str)],
    },
}

impl Files<'_> {
    fn display(&self, rel: &Path) -> String {
        match self {
            Files::Disk(base) => base.join(rel).display().to_string(),
            Files::Embedded { label, .. } => format!("{label}{}", rel.display()),
        }
    }

    /// (name for messages, bytes) of the file at `rel`.
    fn read(&self, rel: &Path, referenced_by: String) -> Result<(String, Vec<u8>), SceneError> {
        let display = self.display(rel);
        let bytes = match self {
            Files::Disk(base) => {
                std::fs::read(base.join(rel)).map_err(|error| SceneError::Read {
                    path: display.clone(),
                    referenced_by,
                    error,
                })?
            }
            Files::Embedded { files, .. } => {
                let key = rel.to_string_lossy().replace('\\', "/");
                let found = files.iter().find(|(name, _)| *name == key);
                found
                    .map(|(_, text)| text.as_bytes().to_vec())
                    .ok_or_else(|| SceneError::Read {
                        path: display.clone(),
                        referenced_by,
                        error: std::io::ErrorKind::NotFound.into(),
                    })?
            }
        };
        Ok((display, bytes))
    }

    fn disk_path(&self, rel: &Path) -> Option<PathBuf> {
        match self {
            Files::Disk(base) => Some(base.join(rel)),
            Files::Embedded { .. } => None,
        }
    }
}

fn build(file: &str, toml_text: &str, files: &Files) -> Result<Scene, SceneError> {
    let mut hash = Fnv1a64::default();
    hash.write(toml_text.as_bytes());
    let f = file::parse(file, toml_text)?;

    let mut luminaires = vec![];
    for (k, l) in f.luminaire.iter().enumerate() {
        let rel = Path::new(&l.path);
        let (_, bytes) = files.read(
            rel,
            format!("referenced by {file}: luminaire[{k}].path = {:?}", l.path),
        )?;
        hash.write(&bytes);
        let Some(path) = files.disk_path(rel) else {
            return Err(SceneError::Unsupported {
                file: file.to_string(),
                field: format!("luminaire[{k}].path"),
                value: format!("{:?}", l.path),
                what: "luminaires in embedded scenes".into(),
            });
        };
        let luminaire = luminaire::Luminaire::load(&path)?;
        // The atlases' texels are part of the content.
        for texel in luminaire.frames().into_iter().flatten().flatten() {
            for c in texel.to_array() {
                hash.write(&c.to_le_bytes());
            }
        }
        luminaires.push(luminaire::PlacedLuminaire::place(file, k, luminaire, l)?);
    }
    let camera = camera::build(file, &f.camera)?;
    let lights = f
        .light
        .iter()
        .enumerate()
        .map(|(i, l)| lights::build(file, i, l))
        .collect::<Result<Vec<_>, _>>()?;
    if let Some(env) = &f.environment {
        environment::check(file, env)?;
    }
    let failure = f
        .failure
        .as_ref()
        .map(|x| failure::build(file, x))
        .transpose()?;

    let mut warnings = Vec::new();
    let mut materials: Vec<Material> = Vec::new();
    let mut textures = Vec::new();
    // Each material's MTL file, for messages (None: the default material).
    let mut material_files: Vec<Option<String>> = Vec::new();
    let mut default_material = None;
    // Per mesh: (OBJ name for messages, its triangles).
    let mut meshes: Vec<(String, Vec<Triangle>)> = Vec::new();
    for (i, m) in f.mesh.iter().enumerate() {
        let rel = Path::new(&m.obj);
        let (obj_file, bytes) = files.read(
            rel,
            format!("referenced by {file}: mesh[{i}].obj = {:?}", m.obj),
        )?;
        hash.write(&bytes);
        let dir = rel.parent().unwrap_or(Path::new(""));
        let mut read_mtl = |name: &str, by: &str| files.read(&dir.join(name), by.to_string());
        let bytes = if m.obj.ends_with(".gz") {
            gunzip(&obj_file, &bytes)?
        } else {
            bytes
        };
        let given_in = format!("{file}: mesh[{i}].groups");
        let groups =
            match (&m.mtl, &m.groups) {
                (Some(mtl), Some(groups)) => Some(obj::GroupMaterials {
                    mtl: mtl.as_str(),
                    groups,
                    given_in: &given_in,
                }),
                (None, None) => None,
                _ => return Err(SceneError::Invalid {
                    file: file.to_string(),
                    field: format!("mesh[{i}]"),
                    value: format!(
                        "mtl {:?}, groups {:?}",
                        m.mtl,
                        m.groups.as_ref().map(|g| g.len())
                    ),
                    problem:
                        "`mtl` and `groups` go together: the MTL's materials for the OBJ's groups"
                            .into(),
                }),
            };
        let mesh = obj::load(
            &obj_file,
            &String::from_utf8_lossy(&bytes),
            &mut read_mtl,
            groups.as_ref(),
        )?;
        for b in &mesh.mtl_bytes {
            hash.write(b);
        }
        warnings.extend(mesh.warnings);
        let offset = materials.len() as u32;
        let texture_offset = textures.len() as u32;
        textures.extend(mesh.textures);
        materials.extend(mesh.materials.into_iter().map(|m| Material {
            albedo_texture: m.albedo_texture.map(|t| t + texture_offset),
            ..m
        }));
        material_files.extend(mesh.material_files.into_iter().map(Some));
        let mut triangles = Vec::with_capacity(mesh.triangles.len());
        for t in mesh.triangles {
            let material = match t.material {
                Some(k) => offset + k,
                None => *default_material.get_or_insert_with(|| {
                    materials.push(Material {
                        name: "default".into(),
                        kd: Vec3::splat(0.5),
                        ks: Vec3::ZERO,
                        ns: 0.0,
                        ke: Vec3::ZERO,
                        albedo_texture: None,
                    });
                    material_files.push(None);
                    materials.len() as u32 - 1
                }),
            };
            triangles.push(Triangle {
                positions: t.positions,
                normals: t.normals,
                material,
                uvs: t.uvs,
            });
        }
        meshes.push((obj_file, triangles));
    }

    let mut environment_sequence = match &f.environment {
        Some(env) => load_environment(file, files, env, &mut hash)?,
        None => vec![],
    };
    let environment = environment_sequence.first().cloned();
    if environment_sequence.len() < 2 {
        environment_sequence.clear();
    }

    coincident::warn_coincident_emitters(&meshes, &materials, &mut warnings);
    let triangles = drop_degenerate(meshes, &mut warnings);
    if triangles.is_empty() {
        let detail = if f.mesh.is_empty() {
            " (it names no [[mesh]])".to_string()
        } else {
            format!(" in its {} mesh file(s)", f.mesh.len())
        };
        return Err(SceneError::Empty {
            file: file.to_string(),
            detail,
        });
    }
    let emits = triangles
        .iter()
        .any(|t| materials[t.material as usize].is_emissive())
        || lights.iter().any(|l| match l {
            super::Light::Point { intensity, .. } | super::Light::Spot { intensity, .. } => {
                intensity.max_element() > 0.0
            }
        })
        || environment
            .iter()
            .chain(&environment_sequence)
            .any(|e| e.texels.iter().any(|t| t.max_element() > 0.0))
        || luminaires.iter().any(|l| l.luminaire.emits());
    if !emits {
        return Err(SceneError::NoLight {
            file: file.to_string(),
        });
    }

    let scene = Scene {
        source: None,
        name: String::new(),
        content_hash: hash.finish(),
        camera,
        triangles,
        materials,
        lights,
        textures,
        environment,
        environment_sequence,
        luminaires,
        failure,
        warnings,
        animation: None,
        load_ms: 0.0,
    };
    let sources = power::PowerSources {
        file,
        material_files: &material_files,
        environment: f.environment.as_ref().map(|e| {
            let map = match (&e.exr, &e.sky) {
                (Some(exr), _) => format!("environment.exr = {exr:?}"),
                (None, Some(sky)) => format!("the sky {sky:?}"),
                (None, None) => "the environment".to_string(),
            };
            (e.scale, map)
        }),
    };
    power::check(&scene, &sources)?;
    let Some(a) = &f.animation else {
        return Ok(scene);
    };
    let animation = Animation::build(
        file,
        a,
        &f.camera,
        &f.light,
        &f.luminaire,
        &scene.materials,
        scene.environment.is_some(),
    )?;
    no_frame_without_light(file, &scene, &animation)?;
    // The power bound at each light's and material's brightest over the frames.
    let (emission, intensity) = animation.brightest(scene.materials.len());
    let mut brightest = scene.clone();
    for (m, s) in brightest.materials.iter_mut().zip(emission) {
        m.ke *= s;
    }
    for (l, i) in brightest.lights.iter_mut().zip(intensity) {
        match l {
            super::Light::Point { intensity, .. } | super::Light::Spot { intensity, .. } => {
                *intensity = i
            }
        }
    }
    power::check(&brightest, &sources)
        .map_err(|e| e.in_context("(at its brightest over [animation])"))?;
    Ok(Scene {
        animation: Some(animation),
        ..scene
    })
}

/// Refuses an animation with a frame in which nothing emits (every light switched off), as a
/// still scene without light is refused: the light tables have nothing to sample there.
fn no_frame_without_light(
    file: &str,
    scene: &Scene,
    animation: &Animation,
) -> Result<(), SceneError> {
    let mut used = vec![false; scene.materials.len()];
    for t in &scene.triangles {
        used[t.material as usize] = true;
    }
    let bright = |e: &Environment| e.texels.iter().any(|t| t.max_element() > 0.0);
    let maps: Vec<bool> = if scene.environment_sequence.is_empty() {
        scene.environment.iter().map(bright).collect()
    } else {
        scene.environment_sequence.iter().map(bright).collect()
    };
    let luminaires = scene.luminaires.iter().any(|l| l.luminaire.emits());
    for f in 0..animation.frames {
        let state = animation.state(f, scene.materials.len())?;
        let emits = luminaires
            || (!maps.is_empty() && maps[f as usize % maps.len()])
            || state.lights.iter().any(|l| match l {
                super::Light::Point { intensity, .. } | super::Light::Spot { intensity, .. } => {
                    intensity.max_element() > 0.0
                }
            })
            || (0..scene.materials.len())
                .any(|m| used[m] && scene.materials[m].is_emissive() && state.emission[m] > 0.0);
        if !emits {
            return Err(SceneError::Invalid {
                file: file.to_string(),
                field: "[animation]".into(),
                value: format!("frame {f}"),
                problem: "nothing emits light in this frame (every light and emitter off); a \
                          frame without light is refused as a still scene without light is: \
                          keep one on"
                    .into(),
            });
        }
    }
    Ok(())
}

/// The maps of `[environment]`, one per frame (one for a still map).
fn load_environment(
    file: &str,
    files: &Files,
    env: &file::EnvironmentFile,
    hash: &mut Fnv1a64,
) -> Result<Vec<Environment>, SceneError> {
    let Some(exr) = &env.exr else {
        let sky = MovingSun::from_file(file, env)?;
        return Ok((0..sky.frames).map(|f| sky.map(f, env.scale)).collect());
    };
    let unsupported_embedded = || SceneError::Unsupported {
        file: file.to_string(),
        field: "environment.exr".into(),
        value: format!("{exr:?}"),
        what: "environment maps in embedded scenes".into(),
    };
    let rels: Vec<PathBuf> = if environment::is_glob(exr) {
        let (dir, pattern) = environment::split_glob(exr);
        let folder = files.disk_path(&dir).ok_or_else(unsupported_embedded)?;
        let found =
            environment::expand_glob(&folder, &pattern).map_err(|error| SceneError::Read {
                path: folder.display().to_string(),
                referenced_by: format!("{file}: environment.exr = {exr:?} (its folder)"),
                error,
            })?;
        if found.is_empty() {
            return Err(SceneError::Invalid {
                file: file.to_string(),
                field: "environment.exr".into(),
                value: format!("{exr:?}"),
                problem: format!("no file in {} matches", folder.display()),
            });
        }
        found
            .iter()
            .map(|p| dir.join(p.file_name().unwrap_or_default()))
            .collect()
    } else {
        vec![PathBuf::from(exr)]
    };
    let mut maps: Vec<Environment> = Vec::with_capacity(rels.len());
    for rel in &rels {
        let (display, bytes) = files.read(
            rel,
            format!("referenced by {file}: environment.exr = {exr:?}"),
        )?;
        hash.write(&bytes);
        let path = files.disk_path(rel).ok_or_else(unsupported_embedded)?;
        let map = environment::read(&display, &path, env.scale)?;
        if let Some(first) = maps.first() {
            if (map.width, map.height) != (first.width, first.height) {
                return Err(SceneError::Invalid {
                    file: display,
                    field: "size".into(),
                    value: format!("{}x{}", map.width, map.height),
                    problem: format!(
                        "every map of the sequence {exr:?} must have the size of the first, {} ({}x{})",
                        first.source.display(),
                        first.width,
                        first.height
                    ),
                });
            }
        }
        maps.push(map);
    }
    Ok(maps)
}

/// Drops triangles of (near) zero area for their own size, with one warning per mesh file
/// that had any.
fn drop_degenerate(
    meshes: Vec<(String, Vec<Triangle>)>,
    warnings: &mut Vec<String>,
) -> Vec<Triangle> {
    let mut kept = Vec::new();
    for (obj_file, triangles) in meshes {
        let (count, kept_before) = (triangles.len(), kept.len());
        kept.extend(
            triangles
                .into_iter()
                .filter(|t| !is_degenerate(t.positions)),
        );
        let dropped = count - (kept.len() - kept_before);
        if dropped > 0 {
            warnings.push(format!(
                "{obj_file}: dropped {dropped} degenerate triangles (area <= {DEGENERATE_AREA:e} \
                 x the square of the triangle's longest edge)"
            ));
        }
    }
    kept
}

/// A gzip-compressed file's contents, read as a stream.
fn gunzip(file: &str, bytes: &[u8]) -> Result<Vec<u8>, SceneError> {
    use std::io::Read as _;
    let mut out = Vec::new();
    flate2::read::GzDecoder::new(bytes)
        .read_to_end(&mut out)
        .map_err(|e| SceneError::File {
            file: file.to_string(),
            message: format!("not a readable gzip file: {e}"),
        })?;
    Ok(out)
}

/// Whether a triangle has (near) zero area for its own size.
pub fn is_degenerate(p: [Vec3; 3]) -> bool {
    let [a, b, c] = p.map(|v| v.as_dvec3());
    let longest2 = (b - a)
        .length_squared()
        .max((c - b).length_squared())
        .max((a - c).length_squared());
    0.5 * obj::double_area(p) <= DEGENERATE_AREA * longest2
}
