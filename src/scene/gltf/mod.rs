//! glTF 2.0 scenes (docs/scenes.md "glTF scenes"): `irad render model.gltf` or `model.glb`
//! reads the default scene's meshes under their nodes' transforms, metallic-roughness
//! materials fitted to irad's Lambert plus Phong (materials.rs), base colour textures,
//! emission (KHR_materials_emissive_strength) as area lights, KHR_lights_punctual point and
//! spot lights (lights.rs) and the first perspective camera (camera.rs). Whatever irad does
//! not model exactly is approximated with a warning naming the file and element, or refused
//! naming the file, the field and its value.
//!
//! The `gltf` crate parses and validates the JSON; irad reads the binary data itself
//! (container.rs: the GLB container; uri.rs: data: URIs and relative files; data.rs: buffers
//! and accessors, checked before they are read), so that bad input is an error, not a panic.
//!
//! One job per module: container, uri, data (bytes), materials, mesh (triangles), lights,
//! camera; this one walks the node tree and assembles the scene.

mod camera;
mod container;
mod data;
mod lights;
mod materials;
mod mesh;
mod uri;

use std::path::{Path, PathBuf};

use glam::{DMat4, DQuat, DVec3};

use super::hash::Fnv1a64;
use super::{power, Camera, Light, Scene, SceneError};

pub use camera::{FRAMING_FOV_Y, HEIGHT, WIDTH};
pub use lights::MIN_CONE;
pub use materials::{metallic_roughness, Fit, DIELECTRIC_F0};

/// The extensions irad reads; others in `extensionsUsed` are warned about (and refused where
/// `extensionsRequired` names them).
const READ_EXTENSIONS: [&str; 2] = ["KHR_lights_punctual", "KHR_materials_emissive_strength"];

/// Whether `path` names a glTF scene (by its extension: `.gltf` or `.glb`).
pub fn is_gltf(path: &Path) -> bool {
    path.extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("gltf") || e.eq_ignore_ascii_case("glb"))
}

/// Loads the glTF scene at `path` with its first camera (the lowest-numbered camera a node of
/// the scene places).
pub fn load(path: &Path) -> Result<Scene, SceneError> {
    load_with_camera(path, None)
}

/// Loads the glTF scene at `path`, seen through `cameras[n]` for `camera` = Some(n) (an error
/// if the file has no such camera or no node places it), else through its first camera.
/// `Scene::name` is the file's stem; the warnings are in `Scene::warnings`, not logged.
pub fn load_with_camera(path: &Path, camera: Option<usize>) -> Result<Scene, SceneError> {
    let start = std::time::Instant::now();
    let (file, bytes) = crate::scene::load::read_scene_file(path)?;
    let mut ctx = Ctx {
        file,
        base: path.parent().unwrap_or(Path::new("")).to_path_buf(),
        hash: Fnv1a64::default(),
        warnings: Vec::new(),
        skipped_directional: None,
    };
    ctx.hash.write(&bytes);
    let glb_by_name = path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("glb"));
    let parts = container::split(&bytes, glb_by_name)
        .map_err(|(field, value, problem)| ctx.invalid(&field, &value, &problem))?;
    let doc = document(&ctx, parts.json)?;
    for ext in doc.extensions_used() {
        if !READ_EXTENSIONS.contains(&ext) {
            ctx.warn(format!("extensionsUsed: {ext} is not read"));
        }
    }
    if doc.animations().len() > 0 {
        ctx.warn(format!(
            "its {} animations are not read (the nodes' own transforms are used)",
            doc.animations().len()
        ));
    }
    let buffers = data::Buffers::load(&mut ctx, &doc, parts.bin)?;
    let placed = walk(&mut ctx, &doc)?;
    let mut materials = materials::Materials::default();
    let mut out = mesh::Out::default();
    let mut lights = Vec::new();
    let mut cameras = Vec::new();
    for (node, world) in &placed {
        let node_label = label(&format!("nodes[{}]", node.index()), node.name());
        if let Some(mesh) = node.mesh() {
            if node.skin().is_some() {
                ctx.warn(format!(
                    "{node_label}: its skin is ignored (the mesh is drawn unskinned under the \
                     node's transform)"
                ));
            }
            let morphs = mesh
                .primitives()
                .any(|p| p.morph_targets().next().is_some());
            let weights = node.weights().or(mesh.weights()).unwrap_or(&[]);
            if morphs && weights.iter().any(|w| *w != 0.0) {
                ctx.warn(format!(
                    "{node_label}: morph target weights are ignored (the base shape is drawn)"
                ));
            }
            mesh::place(
                &mut ctx,
                &doc,
                &buffers,
                &mut materials,
                &mesh,
                &node_label,
                *world,
                &mut out,
            )?;
        }
        if let Some(light) = node.light() {
            let light = lights::punctual(&mut ctx, &light, node.index(), *world, lights.len())?;
            lights.extend(light);
        }
        if let Some(c) = node.camera() {
            cameras.push((c.index(), node.index(), *world));
        }
    }
    if materials.specular {
        ctx.warn(
            "metallic-roughness materials are fitted as Lambert plus normalized Phong at normal \
             incidence (docs/scenes.md \"glTF scenes\"): the Fresnel rise towards grazing \
             angles and GGX's longer tails are left out"
                .into(),
        );
    }
    if out.dropped > 0 {
        ctx.warn(format!(
            "dropped {} degenerate triangles (area <= {:e} x the square of the triangle's \
             longest edge)",
            out.dropped,
            super::DEGENERATE_AREA
        ));
    }
    if out.triangles.is_empty() {
        return Err(SceneError::Empty {
            file: ctx.file,
            detail: " (no mesh of the scene's nodes has triangles)".into(),
        });
    }
    let (camera, chosen) = choose_camera(&mut ctx, &doc, &cameras, camera, &out.triangles)?;
    // Which camera renders is part of what a render shows (references are cached by the hash).
    ctx.hash.write(format!("camera {chosen:?}").as_bytes());
    let emits = out
        .triangles
        .iter()
        .any(|t| materials.list[t.material as usize].is_emissive())
        || lights.iter().any(|l| match l {
            Light::Point { intensity, .. } | Light::Spot { intensity, .. } => {
                intensity.max_element() > 0.0
            }
        });
    // A model without light (most glTF samples: a viewer lights them with an environment) is
    // lit by a uniform white sky, with a warning, so that `irad render model.gltf` renders it.
    let environment = if emits {
        None
    } else {
        let why = match &ctx.skipped_directional {
            Some(field) => format!("its only light, {field}, is directional (irad has none)"),
            None => "it has no light (no emissive material, no point or spot light)".into(),
        };
        ctx.warn(format!(
            "{why}: lit by a uniform white sky of radiance {DEFAULT_SKY} instead (ir and bir \
             decline skies)"
        ));
        ctx.hash.write(b"default sky");
        Some(super::Environment {
            width: 16,
            height: 8,
            texels: vec![glam::Vec3::splat(DEFAULT_SKY); 16 * 8],
            source: PathBuf::from("the default sky of a glTF scene without lights"),
        })
    };
    let scene = Scene {
        source: Some(path.to_path_buf()),
        name: path
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_default(),
        content_hash: ctx.hash.finish(),
        camera,
        triangles: out.triangles,
        materials: materials.list,
        lights,
        textures: materials.textures,
        environment,
        environment_sequence: Vec::new(),
        luminaires: Vec::new(),
        failure: None,
        warnings: ctx.warnings,
        animation: None,
        load_ms: 0.0,
    };
    let material_files = vec![Some(ctx.file.clone()); scene.materials.len()];
    power::check(
        &scene,
        &power::PowerSources {
            file: &ctx.file,
            material_files: &material_files,
            environment: scene
                .environment
                .as_ref()
                .map(|_| (1.0, "the default sky".to_string())),
        },
    )?;
    Ok(Scene {
        load_ms: start.elapsed().as_secs_f64() * 1e3,
        ..scene
    })
}

/// The radiance of the sky a scene without lights gets.
const DEFAULT_SKY: f32 = 1.0;

/// What the loader's parts share: the file's name and folder, the content hash, the warnings.
pub(crate) struct Ctx {
    /// The glTF file, for messages.
    file: String,
    /// Its folder: URIs are relative to it.
    base: PathBuf,
    hash: Fnv1a64,
    warnings: Vec<String>,
    /// The first directional light skipped, for the error when nothing else emits.
    skipped_directional: Option<String>,
}

impl Ctx {
    fn invalid(&self, field: &str, value: &str, problem: &str) -> SceneError {
        SceneError::Invalid {
            file: self.file.clone(),
            field: field.to_string(),
            value: value.to_string(),
            problem: problem.to_string(),
        }
    }

    /// A warning, prefixed with the file.
    fn warn(&mut self, message: String) {
        self.warnings.push(format!("{}: {message}", self.file));
    }
}

/// `field` with the element's name, if it has one: "materials[2] `Gold`".
fn label(field: &str, name: Option<&str>) -> String {
    match name {
        Some(n) => format!("{field} `{n}`"),
        None => field.to_string(),
    }
}

/// The JSON parsed and validated by the `gltf` crate; its errors as irad's, naming the field
/// and its value.
fn document(ctx: &Ctx, json: &[u8]) -> Result<gltf::Document, SceneError> {
    let not_json = |e: &dyn std::fmt::Display| SceneError::File {
        file: ctx.file.clone(),
        message: format!("not glTF 2.0 JSON: {e}"),
    };
    let value: serde_json::Value = serde_json::from_slice(json).map_err(|e| not_json(&e))?;
    let version = value
        .pointer("/asset/version")
        .and_then(|v| v.as_str())
        .unwrap_or("(missing)")
        .to_string();
    if !version.starts_with("2.") {
        return Err(SceneError::Unsupported {
            file: ctx.file.clone(),
            field: "asset.version".into(),
            value: format!("{version:?}"),
            what: "glTF versions other than 2.x".into(),
        });
    }
    let root: gltf::json::Root = serde_json::from_value(value).map_err(|e| not_json(&e))?;
    // The crate's own validation indexes the accessors by each POSITION unchecked (a panic
    // where the index is past them), so those indices are checked first.
    for (m, mesh) in root.meshes.iter().enumerate() {
        for (p, primitive) in mesh.primitives.iter().enumerate() {
            let semantic = gltf::json::validation::Checked::Valid(gltf::Semantic::Positions);
            if let Some(index) = primitive.attributes.get(&semantic) {
                if index.value() >= root.accessors.len() {
                    return Err(ctx.invalid(
                        &format!("meshes[{m}].primitives[{p}].attributes[\"POSITION\"]"),
                        &index.value().to_string(),
                        &format!(
                            "Index out of bounds (the file has {} accessors)",
                            root.accessors.len()
                        ),
                    ));
                }
            }
        }
    }
    gltf::Document::from_json(root).map_err(|e| match e {
        gltf::Error::Validation(errors) if !errors.is_empty() => {
            let (path, error) = &errors[0];
            let path = path.to_string();
            let (field, value) = match path.split_once(" = ") {
                Some((f, v)) => (f.to_string(), v.to_string()),
                None => {
                    let value = serde_json::from_slice::<serde_json::Value>(json)
                        .ok()
                        .and_then(|root| value_at(&root, &path))
                        .unwrap_or_else(|| "(missing)".into());
                    (path, value)
                }
            };
            let more = match errors.len() {
                1 => String::new(),
                n => format!(" (and {} more problems)", n - 1),
            };
            let problem = match error {
                gltf::json::validation::Error::Unsupported => {
                    "an extension the file requires and irad does not read".to_string()
                }
                other => format!("{other} (glTF's schema)"),
            };
            ctx.invalid(&field, &value, &format!("{problem}{more}"))
        }
        other => not_json(&other),
    })
}

/// The JSON text of the value at a validation path such as
/// `meshes[0].primitives[1].attributes["POSITION"]`, cut to 60 characters.
fn value_at(root: &serde_json::Value, path: &str) -> Option<String> {
    let mut v = root;
    let mut rest = path;
    while !rest.is_empty() {
        if let Some(r) = rest.strip_prefix('.') {
            rest = r;
        } else if let Some(r) = rest.strip_prefix("[\"") {
            let end = r.find("\"]")?;
            v = v.get(&r[..end])?;
            rest = &r[end + 2..];
        } else if let Some(r) = rest.strip_prefix('[') {
            let end = r.find(']')?;
            v = v.get(r[..end].parse::<usize>().ok()?)?;
            rest = &r[end + 1..];
        } else {
            let end = rest.find(['.', '[']).unwrap_or(rest.len());
            v = v.get(&rest[..end])?;
            rest = &rest[end..];
        }
    }
    let text = v.to_string();
    Some(match text.char_indices().nth(60) {
        Some((cut, _)) => format!("{}...", &text[..cut]),
        None => text,
    })
}

/// The default scene's nodes, depth first in file order, each with its world transform.
/// Refuses a node with two parents and a root node with a parent (glTF's nodes form disjoint
/// trees), so the walk ends.
fn walk<'a>(
    ctx: &mut Ctx,
    doc: &'a gltf::Document,
) -> Result<Vec<(gltf::Node<'a>, DMat4)>, SceneError> {
    let scene = doc
        .default_scene()
        .or_else(|| doc.scenes().next())
        .ok_or_else(|| SceneError::File {
            file: ctx.file.clone(),
            message: "the file has no scene (`scenes` is empty): nothing to render".into(),
        })?;
    if doc.scenes().len() > 1 {
        ctx.warn(format!(
            "scenes[{}] is read; the file's {} other scenes are not",
            scene.index(),
            doc.scenes().len() - 1
        ));
    }
    let mut parent = vec![None; doc.nodes().len()];
    for node in doc.nodes() {
        for child in node.children() {
            if let Some(p) = parent[child.index()] {
                return Err(ctx.invalid(
                    &format!("nodes[{}].children", node.index()),
                    &child.index().to_string(),
                    &format!(
                        "nodes[{}] is already a child of nodes[{p}] (glTF's nodes form trees)",
                        child.index()
                    ),
                ));
            }
            parent[child.index()] = Some(node.index());
        }
    }
    let roots: Vec<gltf::Node> = scene.nodes().collect();
    for root in &roots {
        if let Some(p) = parent[root.index()] {
            return Err(ctx.invalid(
                &format!("scenes[{}].nodes", scene.index()),
                &root.index().to_string(),
                &format!("a root node of the scene is a child of nodes[{p}]"),
            ));
        }
    }
    let mut placed = Vec::new();
    let mut stack: Vec<(gltf::Node, DMat4)> = roots
        .into_iter()
        .rev()
        .map(|n| (n, DMat4::IDENTITY))
        .collect();
    while let Some((node, parent)) = stack.pop() {
        let world = parent * local(ctx, &node)?;
        let children: Vec<gltf::Node> = node.children().collect();
        stack.extend(children.into_iter().rev().map(|c| (c, world)));
        placed.push((node, world));
    }
    Ok(placed)
}

/// A node's transform (its matrix, or translation * rotation * scale with the rotation
/// normalized), in f64.
fn local(ctx: &Ctx, node: &gltf::Node) -> Result<DMat4, SceneError> {
    let field = format!("nodes[{}]", node.index());
    let fmt = |v: &[f32]| {
        let parts: Vec<String> = v.iter().map(|x| x.to_string()).collect();
        format!("[{}]", parts.join(", "))
    };
    match node.transform() {
        gltf::scene::Transform::Matrix { matrix } => {
            let m = DMat4::from_cols_array_2d(&matrix.map(|c| c.map(f64::from)));
            if !m.is_finite() {
                return Err(ctx.invalid(
                    &format!("{field}.matrix"),
                    &fmt(matrix.as_flattened()),
                    "must be finite",
                ));
            }
            Ok(m)
        }
        gltf::scene::Transform::Decomposed {
            translation,
            rotation,
            scale,
        } => {
            let q = DQuat::from_array(rotation.map(f64::from));
            if !(q.is_finite() && q.length() > 0.0) {
                return Err(ctx.invalid(
                    &format!("{field}.rotation"),
                    &fmt(&rotation),
                    "must be a finite, non-zero quaternion",
                ));
            }
            for (key, v) in [("translation", translation), ("scale", scale)] {
                if !v.iter().all(|x| x.is_finite()) {
                    return Err(ctx.invalid(&format!("{field}.{key}"), &fmt(&v), "must be finite"));
                }
            }
            Ok(DMat4::from_scale_rotation_translation(
                DVec3::from(scale.map(f64::from)),
                q.normalize(),
                DVec3::from(translation.map(f64::from)),
            ))
        }
    }
}

/// The camera and its index: `cameras[n]` where one is asked for, else the lowest-numbered
/// perspective camera a node places, else one framing the triangles (with a warning; index
/// None).
fn choose_camera(
    ctx: &mut Ctx,
    doc: &gltf::Document,
    placed: &[(usize, usize, DMat4)],
    requested: Option<usize>,
    triangles: &[super::Triangle],
) -> Result<(Camera, Option<usize>), SceneError> {
    let count = doc.cameras().len();
    let index = match requested {
        Some(n) if n >= count => {
            let problem = match count {
                0 => "the file has no camera".to_string(),
                1 => "the file has 1 camera: --camera 0 picks it".to_string(),
                _ => format!(
                    "the file has {count} cameras: --camera takes 0 to {}",
                    count - 1
                ),
            };
            return Err(ctx.invalid("cameras", &format!("--camera {n}"), &problem));
        }
        Some(n) => {
            if !placed.iter().any(|(c, ..)| *c == n) {
                return Err(ctx.invalid(
                    &format!("cameras[{n}]"),
                    &format!("--camera {n}"),
                    "no node of the scene places this camera",
                ));
            }
            n
        }
        // The lowest-numbered perspective camera placed (an orthographic one is refused only
        // when asked for), else the lowest placed (refused by name below).
        None => match placed
            .iter()
            .map(|(c, ..)| *c)
            .filter(|&c| {
                doc.cameras().nth(c).is_some_and(|cam| {
                    matches!(cam.projection(), gltf::camera::Projection::Perspective(_))
                })
            })
            .min()
            .or_else(|| placed.iter().map(|(c, ..)| *c).min())
        {
            Some(n) => n,
            None => {
                let why = match count {
                    0 => "no camera".to_string(),
                    n => format!("none of its {n} cameras is placed by a node of the scene"),
                };
                ctx.warn(format!(
                    "{why}: a {FRAMING_FOV_Y}-degree camera on the +z side of the scene's \
                     bounds looks down -z at their centre, {WIDTH} x {HEIGHT}"
                ));
                return Ok((camera::framing(ctx, triangles)?, None));
            }
        },
    };
    let (_, node, world) = placed
        .iter()
        .find(|(c, ..)| *c == index)
        .copied()
        .ok_or_else(|| ctx.invalid("cameras", &index.to_string(), "not placed"))?;
    Ok((
        camera::perspective(ctx, doc, index, node, world)?,
        Some(index),
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn values_are_found_by_validation_paths() {
        let root: serde_json::Value = serde_json::from_str(
            r#"{"meshes":[{"primitives":[{"attributes":{"POSITION":7}}]}],"a":{"b":"c"}}"#,
        )
        .unwrap();
        assert_eq!(
            value_at(&root, "meshes[0].primitives[0].attributes[\"POSITION\"]").as_deref(),
            Some("7")
        );
        assert_eq!(value_at(&root, "a.b").as_deref(), Some("\"c\""));
        assert_eq!(value_at(&root, "a.x"), None);
        assert_eq!(value_at(&root, "meshes[3]"), None);
    }

    #[test]
    fn gltf_and_glb_are_recognised_by_extension() {
        assert!(is_gltf(Path::new("a/b.gltf")));
        assert!(is_gltf(Path::new("b.GLB")));
        assert!(!is_gltf(Path::new("scene.toml")));
        assert!(!is_gltf(Path::new("gltf")));
    }
}
