//! A `Scene` as a Mitsuba 3 scene (`<scene version="3.0.0">`), for cross-checking irad's
//! images in Mitsuba: `DIR/scene.xml`, one PLY mesh per material (ply.rs), the albedo
//! textures' images (texture.rs) and, with an environment, `DIR/environment.exr`. Render it
//! with an RGB variant (`scalar_rgb`, `llvm_ad_rgb`, `cuda_ad_rgb`): spectral variants upsample
//! every RGB value and multiply emitters by D65, which irad does not.
//!
//! Exact (the same function of the scene as irad's, docs/DESIGN.md "Conventions"):
//! - camera: `perspective`, `fov_axis` y, `to_world` `lookat` with irad's position, target and
//!   up, `hdrfilm` with a `box` filter (pixel averages). Mitsuba's `lookat` puts camera +x
//!   to the left (left = up x dir) and its film puts camera -x at the image's right, so the
//!   image's right is dir x up, irad's `right`: no flip, no mirror (tests/export.rs recomputes
//!   Mitsuba's rays).
//! - meshes: irad's triangles, counter-clockwise, with irad's per-corner shading normals
//!   (which irad's BSDFs use; the geometric normal where the OBJ has no `vn`), every triangle
//!   its own three vertices; a mesh with texture coordinates (a textured material's, or any
//!   that are not all zero) has irad's (v up) as PLY `u v` and its shape `flip_tex_coords`,
//!   which makes them Mitsuba's (v = 0 at the image's top; Mitsuba 3.4 or later reads it).
//! - Lambert: `twosided` `diffuse`, reflectance Kd (f = Kd / pi on both sides, as irad).
//! - albedo textures: a `bitmap` reflectance (texture.rs): the image file copied, with its
//!   wrap mode; Kd 1 or grey (a blend with black) exactly, other Kd baked into the image.
//! - emission: an `area` emitter with radiance Ke on the material's shape (one-sided, on the
//!   normal's side; counter-clockwise corners keep irad's side), besides the shape's BSDF.
//! - point lights: `point`, intensity in W/sr as irad's.
//! - environment: `envmap` with the identity transform, whose angular mapping
//!   u = atan2(x, -z) / (2 pi), v = acos(y) / pi is irad's; radiance already times the scene's
//!   `environment.scale`, so Mitsuba's `scale` is left at 1.
//!
//! Approximate (each in `MitsubaExport::approximations` and an XML comment):
//! - the Phong lobe Ks (Ns + 2) / (2 pi) cos^Ns: a Beckmann `roughconductor` (no Fresnel:
//!   `material` none) blended with the diffuse part (bsdf.rs): the same lobe width and albedo
//!   at normal incidence, but the Phong lobe's albedo falls as about cos(theta_o) away from
//!   it and the microfacet lobe's does not;
//! - spot falloff: Mitsuba ramps linearly in angle from `beam_width` to `cutoff_angle`; fitted
//!   to irad's smoothstep in cos(theta) at the same power (spot.rs);
//! - the environment's texels: Mitsuba interpolates bilinearly between texel centres, irad is
//!   piecewise constant; the map is upsampled so they agree away from texel edges, each texel
//!   with its own power (envmap.rs);
//! - a map sequence (glob or procedural sky): frame 0 only;
//! - interpolated shading normals: irad also requires both directions on one side of the
//!   geometric normal; Mitsuba looks at the shading normal only;
//! - a coloured Kd times a texture, baked into an 8-bit PNG; a texture not read from an 8-bit
//!   PNG or JPEG written as one; different wrap modes on u and v (texture.rs).
//!
//! Refused: light-field luminaires (Mitsuba has no such emitter).

use std::path::{Path, PathBuf};

use glam::Vec3;

use super::ply::{self, PlyTriangle};
use crate::scene::{Environment, Light, Material, Scene};

pub mod bsdf;
pub mod envmap;
pub mod spot;
pub mod texture;

use bsdf::{phong_alpha, split_glossy, GlossySplit};
use envmap::{environment_factor, resample_environment};
use spot::fit_spot;

/// What `write_mitsuba` wrote.
#[derive(Clone, Debug, PartialEq)]
pub struct MitsubaExport {
    /// `DIR/scene.xml`.
    pub xml: PathBuf,
    /// The files it references, in `DIR`: the PLY meshes in material order, each followed by
    /// the texture images it is the first to use, then the EXR.
    pub files: Vec<PathBuf>,
    /// What Mitsuba does not reproduce exactly, one line each, for the CLI to print.
    pub approximations: Vec<String>,
}

/// Why a scene could not be exported. `scene` is the scene file (or the scene's name for a
/// scene built in code).
#[derive(Debug, thiserror::Error)]
pub enum ExportError {
    #[error(
        "{scene}: Mitsuba has no light-field luminaires (the scene places {count}); remove its \
         [[luminaire]] entries (or replace them with spot lights) to export it"
    )]
    Luminaires { scene: String, count: usize },
    /// A value Mitsuba cannot be given (a scene built in code, not one `scene::load` checked).
    #[error("{scene}: {field} = {value}: {problem}")]
    Invalid {
        scene: String,
        field: String,
        value: String,
        problem: String,
    },
    /// A file of the export could not be written.
    #[error("{path}: cannot write the {what}: {error}")]
    Write {
        path: String,
        what: String,
        error: std::io::Error,
    },
    /// The environment map could not be written as EXR.
    #[error("{path}: cannot write the environment map: {message}")]
    Exr { path: String, message: String },
    /// A texture could not be written as PNG.
    #[error("{path}: cannot write the texture: {message}")]
    Texture { path: String, message: String },
}

/// Writes `scene` as a Mitsuba 3 scene into `dir` (created if missing; files of an earlier
/// export of the same names are overwritten). The module doc lists the mapping.
pub fn write_mitsuba(scene: &Scene, dir: &Path) -> Result<MitsubaExport, ExportError> {
    let label = scene
        .source
        .as_ref()
        .map(|p| p.display().to_string())
        .unwrap_or_else(|| scene.name.clone());
    if !scene.luminaires.is_empty() {
        return Err(ExportError::Luminaires {
            scene: label,
            count: scene.luminaires.len(),
        });
    }
    check(&label, scene)?;
    std::fs::create_dir_all(dir).map_err(|error| ExportError::Write {
        path: dir.display().to_string(),
        what: "export folder".into(),
        error,
    })?;

    let mut xml = Xml::default();
    write_header(&mut xml, &label);
    write_sensor(&mut xml, scene);
    let Written {
        mut files,
        mut approximations,
    } = write_meshes(&mut xml, scene, dir)?;
    for (k, light) in scene.lights.iter().enumerate() {
        if let Some(note) = write_light(&mut xml, k, light) {
            approximations.push(note);
        }
    }
    if let Some(env) = &scene.environment {
        let (path, notes) = write_environment(&mut xml, scene, env, dir)?;
        files.push(path);
        approximations.extend(notes);
    }
    xml.close("scene");

    let xml_path = dir.join("scene.xml");
    std::fs::write(&xml_path, xml.text).map_err(|error| ExportError::Write {
        path: xml_path.display().to_string(),
        what: "scene XML".into(),
        error,
    })?;
    Ok(MitsubaExport {
        xml: xml_path,
        files,
        approximations,
    })
}

/// Files a part of the export wrote and its approximation notes, in order.
struct Written {
    files: Vec<PathBuf>,
    approximations: Vec<String>,
}

/// The XML declaration, the comment on how to render, and `<scene>` opened with the `spp`
/// and `max_depth` defaults and the `path` integrator.
fn write_header(xml: &mut Xml, label: &str) {
    xml.line(r#"<?xml version="1.0" encoding="utf-8"?>"#);
    xml.comment(&format!(
        "Exported by irad (irad export mitsuba) from {label}. Render with an RGB variant \
         (scalar_rgb, llvm_ad_rgb, cuda_ad_rgb). Override the defaults with -D spp=N or \
         -D max_depth=N (Mitsuba's max_depth N is irad's N - 1 scattering events; -1: \
         unbounded, like irad's reference at its default 1024)."
    ));
    xml.open("scene", &[("version", "3.0.0")]);
    xml.leaf("default", &[("name", "spp"), ("value", "256")]);
    xml.leaf("default", &[("name", "max_depth"), ("value", "-1")]);
    xml.open("integrator", &[("type", "path")]);
    xml.leaf("integer", &[("name", "max_depth"), ("value", "$max_depth")]);
    xml.close("integrator");
}

/// One PLY mesh and `<shape>` per material with triangles, in material order; the notes of
/// their BSDFs, then those on their normals.
fn write_meshes(xml: &mut Xml, scene: &Scene, dir: &Path) -> Result<Written, ExportError> {
    let mut files = Vec::new();
    let mut approximations = Vec::new();
    let mut flat_only = Vec::new();
    let mut smooth = Vec::new();
    let mut textures = texture::TextureFiles::default();
    for (index, triangles) in material_groups(scene).iter().enumerate() {
        if triangles.is_empty() {
            continue;
        }
        let m = &scene.materials[index];
        let normals = choose_normals(m, triangles);
        match normals {
            Normals::Shading { smooth: true } => smooth.push(format!("`{}`", m.name)),
            Normals::Face => flat_only.push(format!("`{}`", m.name)),
            Normals::Shading { smooth: false } => {}
        }
        let mesh = Mesh {
            index,
            material: m,
            triangles,
            normals,
        };
        let (path, notes) = write_mesh(xml, scene, dir, &mesh, &mut textures)?;
        files.push(path);
        files.append(&mut textures.files);
        approximations.extend(notes);
    }
    for note in normals_notes(&smooth, &flat_only) {
        xml.comment(&note);
        approximations.push(note);
    }
    Ok(Written {
        files,
        approximations,
    })
}

/// One material's mesh to write.
struct Mesh<'a> {
    index: usize,
    material: &'a Material,
    triangles: &'a [&'a crate::scene::Triangle],
    normals: Normals,
}

/// The diffuse reflectance `write_bsdf` writes for `m` (Kd, or Kd / (1 - w) in a glossy
/// blend); None without a diffuse part.
fn diffuse_factor(m: &Material) -> Option<[f64; 3]> {
    if m.kd.max_element() <= 0.0 {
        return None;
    }
    if m.ks.max_element() <= 0.0 {
        return Some(m.kd.as_dvec3().to_array());
    }
    match split_glossy(m.kd, m.ks) {
        GlossySplit::SpecularOnly => None,
        GlossySplit::Blend { diffuse, .. } => Some(diffuse),
    }
}

/// Material `index`'s triangles as `DIR/mesh-NNN-name.ply` with `normals` (and texture
/// coordinates where it has any), its texture's image (texture.rs), and its `<shape>` with
/// its BSDF and, when emissive, its area emitter. Returns the PLY's path and the
/// approximation notes of the texture and the BSDF.
fn write_mesh(
    xml: &mut Xml,
    scene: &Scene,
    dir: &Path,
    mesh: &Mesh,
    textures: &mut texture::TextureFiles,
) -> Result<(PathBuf, Vec<String>), ExportError> {
    let (index, m, triangles, normals) = (mesh.index, mesh.material, mesh.triangles, mesh.normals);
    let name = format!("mesh-{index:03}-{}", file_stem(&m.name));
    let file = format!("{name}.ply");
    let with_uvs = m.albedo_texture.is_some()
        || triangles
            .iter()
            .any(|t| t.uvs.iter().any(|&uv| uv != glam::Vec2::ZERO));
    let mesh = ply_triangles(triangles, normals);
    let path = dir.join(&file);
    let comment = format!("irad material {}", m.name);
    ply::write(&path, &comment, &mesh, with_uvs).map_err(|error| ExportError::Write {
        path: path.display().to_string(),
        what: format!("mesh of material `{}`", m.name),
        error,
    })?;
    let (bitmap, mut notes) = match (m.albedo_texture, diffuse_factor(m)) {
        (Some(t), Some(factor)) => {
            let (b, notes) = textures.reflectance(scene, t, factor, dir, &name, &m.name)?;
            (Some(b), notes)
        }
        _ => (None, Vec::new()),
    };
    for note in &notes {
        xml.comment(note);
    }

    xml.comment(&format!(
        "material `{}`: {} triangles{}",
        m.name,
        mesh.len(),
        match normals {
            Normals::Face => ", face normals (see the emitter)",
            Normals::Shading { smooth: true } => ", irad's interpolated shading normals",
            Normals::Shading { smooth: false } => "",
        }
    ));
    xml.open("shape", &[("type", "ply"), ("id", &name)]);
    xml.string("filename", &file);
    if with_uvs {
        xml.comment(
            "Texture coordinates as irad's (v up, OBJ's convention); flip_tex_coords makes \
             them Mitsuba's (v = 0 at the image's top). Mitsuba 3.4 or later.",
        );
        xml.leaf("boolean", &[("name", "flip_tex_coords"), ("value", "true")]);
    }
    notes.extend(write_bsdf(xml, m, bitmap.as_ref()));
    if m.is_emissive() {
        if matches!(normals, Normals::Face) {
            xml.comment(
                "Mitsuba emits on the side of the interpolated shading normal, irad on \
                 the geometric normal's: some corner normal here points to the other \
                 side, so the mesh has face normals",
            );
        }
        xml.open("emitter", &[("type", "area")]);
        xml.rgb("radiance", m.ke);
        xml.close("emitter");
    }
    xml.close("shape");
    Ok((path, notes))
}

/// The triangles with the corner normals `normals` chose.
fn ply_triangles(triangles: &[&crate::scene::Triangle], normals: Normals) -> Vec<PlyTriangle> {
    triangles
        .iter()
        .map(|t| {
            let normals = match normals {
                Normals::Face => [geometric_normal(t.positions); 3],
                Normals::Shading { .. } => t.normals,
            };
            PlyTriangle {
                positions: t.positions,
                normals,
                uvs: t.uvs,
            }
        })
        .collect()
}

/// The approximation notes on normals: the materials with interpolated shading normals,
/// then the emissive ones given face normals (none for an empty list).
fn normals_notes(smooth: &[String], flat_only: &[String]) -> Vec<String> {
    let mut notes = Vec::new();
    if !smooth.is_empty() {
        notes.push(format!(
            "materials {}: interpolated shading normals; irad also needs the incident and \
             outgoing directions on one side of the geometric normal, Mitsuba checks the \
             shading normal only (differs where the two disagree, near silhouettes)",
            smooth.join(", ")
        ));
    }
    if !flat_only.is_empty() {
        notes.push(format!(
            "emissive materials {}: face normals instead of irad's shading normals (some \
             point away from the geometric normal, and Mitsuba would emit on their side)",
            flat_only.join(", ")
        ));
    }
    notes
}

/// The environment map upsampled (envmap.rs) as `DIR/environment.exr`, and its `envmap`
/// emitter. Returns the EXR's path and the notes: the upsampling, and a sequence's frame 0.
fn write_environment(
    xml: &mut Xml,
    scene: &Scene,
    env: &Environment,
    dir: &Path,
) -> Result<(PathBuf, Vec<String>), ExportError> {
    let file = "environment.exr";
    let path = dir.join(file);
    let k = environment_factor(env.width, env.height);
    let map = resample_environment(env, k);
    crate::image::exr::write(&path, &map).map_err(|e| ExportError::Exr {
        path: path.display().to_string(),
        message: format!("{e:#}"),
    })?;
    let mut notes = vec![format!(
        "environment map {}x{}: Mitsuba interpolates bilinearly, irad is piecewise \
         constant; written upsampled {k}x to {}x{} (each texel a block, rows on texel \
         edges weighted so every texel keeps its power), so the radiance is irad's \
         except within {:.4} of a texel width of its left and right edges and {:.4} of a \
         texel height of its top and bottom edges, where it ramps linearly between the \
         two texels",
        env.width,
        env.height,
        map.width,
        map.height,
        0.5 / k as f64,
        1.0 / k as f64,
    )];
    if !scene.environment_sequence.is_empty() {
        notes.push(format!(
            "the environment is a sequence of {} maps (an exr glob or a procedural sky): \
             Mitsuba gets frame 0 only",
            scene.environment_sequence.len()
        ));
    }
    for note in &notes {
        xml.comment(note);
    }
    xml.comment(
        "Identity to_world: Mitsuba's (u, v) = (atan2(x, -z) / 2 pi, acos(y) / pi) is \
         irad's. Radiance already times the scene's environment.scale.",
    );
    xml.open("emitter", &[("type", "envmap")]);
    xml.string("filename", file);
    xml.close("emitter");
    Ok((path, notes))
}

/// Refuses values Mitsuba cannot parse (non-finite) and material indices out of range: a
/// scene from `scene::load` passes; one built in code may not.
fn check(label: &str, scene: &Scene) -> Result<(), ExportError> {
    let invalid = |field: String, value: String, problem: &str| ExportError::Invalid {
        scene: label.to_string(),
        field,
        value,
        problem: problem.to_string(),
    };
    let finite = |v: Vec3| v.is_finite();
    let c = &scene.camera;
    if !(finite(c.position) && finite(c.look_at) && finite(c.up)) {
        return Err(invalid(
            "camera".into(),
            format!("{:?} -> {:?}, up {:?}", c.position, c.look_at, c.up),
            "must be finite",
        ));
    }
    for m in &scene.materials {
        if !(finite(m.kd) && finite(m.ks) && m.ns.is_finite() && finite(m.ke)) {
            return Err(invalid(
                format!("material `{}`", m.name),
                format!("Kd {} Ks {} Ns {} Ke {}", m.kd, m.ks, m.ns, m.ke),
                "must be finite",
            ));
        }
    }
    for m in &scene.materials {
        if let Some(t) = m.albedo_texture {
            if t as usize >= scene.textures.len() {
                return Err(invalid(
                    format!("material `{}` albedo_texture", m.name),
                    t.to_string(),
                    &format!("the scene has {} textures", scene.textures.len()),
                ));
            }
        }
    }
    for (k, t) in scene.textures.iter().enumerate() {
        if t.width == 0 || t.height == 0 || t.texels.len() != t.width as usize * t.height as usize {
            return Err(invalid(
                format!("texture {k}"),
                format!("{}x{}, {} texels", t.width, t.height, t.texels.len()),
                "must be a non-empty width x height texels",
            ));
        }
    }
    for (k, t) in scene.triangles.iter().enumerate() {
        if !t.uvs.iter().all(|uv| uv.is_finite()) {
            return Err(invalid(
                format!("triangle {k} uvs"),
                format!("{:?}", t.uvs),
                "must be finite",
            ));
        }
        if t.material as usize >= scene.materials.len() {
            return Err(invalid(
                format!("triangle {k} material"),
                t.material.to_string(),
                &format!("the scene has {} materials", scene.materials.len()),
            ));
        }
        if !t.positions.iter().chain(&t.normals).all(|v| v.is_finite()) {
            return Err(invalid(
                format!("triangle {k}"),
                format!("{:?} normals {:?}", t.positions, t.normals),
                "must be finite",
            ));
        }
    }
    for (k, l) in scene.lights.iter().enumerate() {
        let (p, i, d) = match l {
            Light::Point {
                position,
                intensity,
            } => (*position, *intensity, Vec3::Y),
            Light::Spot {
                position,
                intensity,
                direction,
                ..
            } => (*position, *intensity, *direction),
        };
        if !(finite(p) && finite(i) && finite(d)) || d.length_squared() == 0.0 {
            return Err(invalid(
                format!("light[{k}]"),
                format!("{l:?}"),
                "must be finite (with a non-zero direction)",
            ));
        }
    }
    Ok(())
}

/// The scene's triangles by material index.
fn material_groups(scene: &Scene) -> Vec<Vec<&crate::scene::Triangle>> {
    let mut groups = vec![Vec::new(); scene.materials.len()];
    for t in &scene.triangles {
        groups[t.material as usize].push(t);
    }
    groups
}

/// Which normals a material's mesh gets.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Normals {
    /// irad's per-corner shading normals, which irad's BSDFs use (interpolated, the geometric
    /// normal where the OBJ gave none); `smooth` when some differ from the geometric normal.
    Shading { smooth: bool },
    /// The geometric normal on every corner.
    Face,
}

/// irad's shading normals reproduce irad's shading exactly, and equal face normals for meshes
/// with no `vn`. An emissive mesh keeps them only while every corner normal is on its
/// triangle's geometric side: Mitsuba's area emitter emits on the side of the interpolated
/// shading normal, irad on the geometric normal's (a convex combination of normals in one
/// open half-space stays in it, so corners on the geometric side keep the whole triangle so).
fn choose_normals(m: &Material, triangles: &[&crate::scene::Triangle]) -> Normals {
    let mut smooth = false;
    for t in triangles {
        let ng = geometric_normal(t.positions);
        for n in t.normals {
            let c = n.dot(ng);
            if m.is_emissive() && c <= 0.0 {
                return Normals::Face;
            }
            smooth |= c < 1.0 - 1e-6;
        }
    }
    Normals::Shading { smooth }
}

/// The unit normal on the counter-clockwise side, as Mitsuba computes it.
fn geometric_normal(p: [Vec3; 3]) -> Vec3 {
    (p[1] - p[0]).cross(p[2] - p[0]).normalize_or_zero()
}

/// A material name as part of a file name and XML id: ASCII letters, digits, `-` and `_`,
/// others `_`, at most 40 characters.
fn file_stem(name: &str) -> String {
    let s: String = name
        .chars()
        .take(40)
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '-' || c == '_' {
                c
            } else {
                '_'
            }
        })
        .collect();
    if s.is_empty() {
        "unnamed".into()
    } else {
        s
    }
}

fn write_sensor(xml: &mut Xml, scene: &Scene) {
    let c = &scene.camera;
    // Mitsuba starts camera rays at near_clip and ends them at far_clip (along the axis);
    // irad clips nothing, so both are put beyond the scene's reach.
    let reach = scene
        .triangles
        .iter()
        .flat_map(|t| t.positions)
        .map(|p| (p - c.position).length())
        .fold(0.0f32, f32::max);
    let far = (4.0 * reach).max(1e4);
    let near = (1e-5 * reach).clamp(1e-7, 1e-2);
    xml.comment(&format!(
        "irad's camera: vertical fov {} degrees, {}x{} pixels, box-filtered (pixel \
         averages). Mitsuba's lookat has +x to the left and its film maps -x to the image's \
         right, so the image is irad's, not mirrored. near_clip / far_clip put beyond the \
         scene (irad clips nothing).",
        c.fov_y, c.width, c.height
    ));
    xml.open("sensor", &[("type", "perspective")]);
    xml.string("fov_axis", "y");
    xml.float("fov", c.fov_y);
    xml.float("near_clip", near);
    xml.float("far_clip", far);
    xml.open("transform", &[("name", "to_world")]);
    xml.leaf(
        "lookat",
        &[
            ("origin", &list(c.position)),
            ("target", &list(c.look_at)),
            ("up", &list(c.up)),
        ],
    );
    xml.close("transform");
    xml.open("sampler", &[("type", "independent")]);
    xml.leaf("integer", &[("name", "sample_count"), ("value", "$spp")]);
    xml.close("sampler");
    xml.open("film", &[("type", "hdrfilm")]);
    xml.leaf(
        "integer",
        &[("name", "width"), ("value", &c.width.to_string())],
    );
    xml.leaf(
        "integer",
        &[("name", "height"), ("value", &c.height.to_string())],
    );
    xml.string("pixel_format", "rgb");
    xml.string("component_format", "float32");
    xml.leaf("rfilter", &[("type", "box")]);
    xml.close("film");
    xml.close("sensor");
}

/// A `diffuse` BSDF of reflectance `rgb`, or of the texture `bitmap` (which stands for `rgb`
/// times the material's texture: texture.rs).
fn write_diffuse(xml: &mut Xml, rgb: [f64; 3], bitmap: Option<&texture::Bitmap>) {
    let Some(b) = bitmap else {
        xml.open("bsdf", &[("type", "diffuse")]);
        xml.reflectance("reflectance", rgb);
        xml.close("bsdf");
        return;
    };
    let textured = |xml: &mut Xml| {
        xml.open("bsdf", &[("type", "diffuse")]);
        xml.open("texture", &[("type", "bitmap"), ("name", "reflectance")]);
        xml.string("filename", &b.file);
        xml.string("wrap_mode", b.wrap_mode);
        xml.close("texture");
        xml.close("bsdf");
    };
    match b.blend {
        None => textured(xml),
        Some(g) => {
            xml.comment(&format!(
                "reflectance {g} times the texture: (1 - {g}) black + {g} the bitmap"
            ));
            xml.open("bsdf", &[("type", "blendbsdf")]);
            xml.float("weight", g);
            xml.open("bsdf", &[("type", "diffuse")]);
            xml.rgb("reflectance", Vec3::ZERO);
            xml.close("bsdf");
            textured(xml);
            xml.close("bsdf");
        }
    }
}

/// Writes the material's BSDF, its diffuse part `bitmap` where it has one; returns the
/// approximation note of a Phong lobe.
fn write_bsdf(xml: &mut Xml, m: &Material, bitmap: Option<&texture::Bitmap>) -> Option<String> {
    let glossy = m.ks.max_element() > 0.0;
    xml.open("bsdf", &[("type", "twosided")]);
    if !glossy {
        write_diffuse(xml, m.kd.as_dvec3().to_array(), bitmap);
        xml.close("bsdf");
        return None;
    }
    let alpha = phong_alpha(m.ns);
    let note = format!(
        "material `{}`: Phong lobe Ks {} Ns {} as a Beckmann microfacet lobe (roughconductor, \
         no Fresnel) with alpha = 1 / sqrt(2 Ns + 1) = {alpha}: the same width and albedo at \
         normal incidence; away from it the Phong lobe reflects about cos(theta_o) of Ks and \
         the microfacet lobe nearly all of it (brighter highlights in Mitsuba, about \
         1 / cos(theta_o) for narrow lobes), and it is stretched off the mirror direction \
         towards grazing angles",
        m.name,
        list(m.ks),
        m.ns
    );
    xml.comment(&note);
    let split = split_glossy(m.kd, m.ks);
    let conductor = |xml: &mut Xml, specular: [f64; 3]| {
        xml.open("bsdf", &[("type", "roughconductor")]);
        xml.string("distribution", "beckmann");
        xml.float("alpha", alpha);
        xml.reflectance("specular_reflectance", specular);
        xml.close("bsdf");
    };
    match split {
        GlossySplit::SpecularOnly => conductor(xml, m.ks.as_dvec3().to_array()),
        GlossySplit::Blend {
            weight,
            diffuse,
            specular,
        } => {
            xml.comment(&format!(
                "f = (1 - w) diffuse + w roughconductor = Kd / pi + Ks lobe with w = max Ks / \
                 (max Kd + max Ks) = {}, diffuse reflectance Kd / (1 - w), specular \
                 reflectance Ks / w",
                weight as f32
            ));
            xml.open("bsdf", &[("type", "blendbsdf")]);
            xml.float("weight", weight as f32);
            write_diffuse(xml, diffuse, bitmap);
            conductor(xml, specular);
            xml.close("bsdf");
        }
    }
    xml.close("bsdf");
    Some(note)
}

/// Writes light `k`; returns the approximation note of a spot light.
fn write_light(xml: &mut Xml, k: usize, light: &Light) -> Option<String> {
    match *light {
        Light::Point {
            position,
            intensity,
        } => {
            xml.comment(&format!("light[{k}]: point"));
            xml.open("emitter", &[("type", "point")]);
            let [x, y, z] = position.to_array().map(|v| v.to_string());
            xml.leaf(
                "point",
                &[("name", "position"), ("x", &x), ("y", &y), ("z", &z)],
            );
            xml.rgb("intensity", intensity);
            xml.close("emitter");
            None
        }
        Light::Spot {
            position,
            intensity,
            direction,
            cone_angle,
            falloff_angle,
        } => {
            let fit = fit_spot(cone_angle, falloff_angle);
            let note = if fit.max_difference == 0.0 {
                None
            } else {
                Some(format!(
                    "light[{k}] (spot, cone {cone_angle}, falloff {falloff_angle} degrees): \
                     irad's smoothstep(cos falloff, cos cone, cos theta) as Mitsuba's linear \
                     ramp in theta, beam_width {:.4}, cutoff_angle {:.4} degrees: the same \
                     power, intensities differing by up to {:.1}% of the peak",
                    fit.beam_width,
                    fit.cutoff_angle,
                    100.0 * fit.max_difference
                ))
            };
            xml.comment(&format!("light[{k}]: spot"));
            if let Some(note) = &note {
                xml.comment(note);
            }
            let d = direction.normalize();
            // The profile is symmetric about the axis: any up not along it will do.
            let up = if d.y.abs() < 0.9 { Vec3::Y } else { Vec3::X };
            xml.open("emitter", &[("type", "spot")]);
            xml.open("transform", &[("name", "to_world")]);
            xml.leaf(
                "lookat",
                &[
                    ("origin", &list(position)),
                    ("target", &list(position + d)),
                    ("up", &list(up)),
                ],
            );
            xml.close("transform");
            xml.rgb("intensity", intensity);
            xml.float("cutoff_angle", fit.cutoff_angle as f32);
            xml.float("beam_width", fit.beam_width as f32);
            xml.close("emitter");
            note
        }
    }
}

/// "x, y, z" as Mitsuba's XML writes a vector.
fn list(v: Vec3) -> String {
    format!("{}, {}, {}", v.x, v.y, v.z)
}

/// A tiny indenting XML writer.
#[derive(Default)]
struct Xml {
    text: String,
    depth: usize,
}

impl Xml {
    fn line(&mut self, s: &str) {
        for _ in 0..self.depth {
            self.text.push_str("    ");
        }
        self.text.push_str(s);
        self.text.push('\n');
    }

    fn tag(name: &str, attrs: &[(&str, &str)], end: &str) -> String {
        let mut s = format!("<{name}");
        for (k, v) in attrs {
            s.push_str(&format!(" {k}=\"{}\"", escape(v)));
        }
        s.push_str(end);
        s
    }

    fn open(&mut self, name: &str, attrs: &[(&str, &str)]) {
        self.line(&Self::tag(name, attrs, ">"));
        self.depth += 1;
    }

    fn close(&mut self, name: &str) {
        self.depth -= 1;
        self.line(&format!("</{name}>"));
    }

    fn leaf(&mut self, name: &str, attrs: &[(&str, &str)]) {
        self.line(&Self::tag(name, attrs, "/>"));
    }

    fn comment(&mut self, text: &str) {
        // "--" may not appear in a comment, nor "-" end it.
        let mut t = text.replace("--", "- -");
        while t.contains("--") {
            t = t.replace("--", "- -");
        }
        if t.ends_with('-') {
            t.push(' ');
        }
        self.line(&format!("<!-- {t} -->"));
    }

    fn string(&mut self, name: &str, value: &str) {
        self.leaf("string", &[("name", name), ("value", value)]);
    }

    fn float(&mut self, name: &str, value: f32) {
        self.leaf("float", &[("name", name), ("value", &value.to_string())]);
    }

    fn rgb(&mut self, name: &str, v: Vec3) {
        self.leaf("rgb", &[("name", name), ("value", &list(v))]);
    }

    /// A reflectance: `<rgb>` within [0, 1], else an `srgb` spectrum marked unbounded (Mitsuba
    /// refuses a bounded reflectance over 1).
    fn reflectance(&mut self, name: &str, v: [f64; 3]) {
        let v = Vec3::from(v.map(|c| c as f32));
        if v.max_element() <= 1.0 {
            self.rgb(name, v);
        } else {
            self.open("spectrum", &[("type", "srgb"), ("name", name)]);
            self.rgb("color", v);
            self.leaf("boolean", &[("name", "unbounded"), ("value", "true")]);
            self.close("spectrum");
        }
    }
}

fn escape(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}
