//! OBJ meshes through tobj 4: faces triangulated as fans, materials from the `mtllib` files
//! (parsed by mtl.rs), shading normals per corner. tobj reports no line numbers, panics on
//! some malformed input and, for a corner without `vn`, silently reuses the previous corner's
//! normal; so every line tobj would read is first checked here (with its line number) and
//! rewritten in a form tobj handles exactly: positions already divided by `w`, absolute
//! indices, and an explicit `vn` on every corner (a zero sentinel where the file gives none,
//! which becomes the geometric normal).

use std::cell::Cell;
use std::path::Path;

use glam::{DVec3, Vec3};

use super::file::fmt3;
use super::{mtl, texture, Material, SceneError, Texture, Wrap};
use glam::Vec2;

/// A triangle as the OBJ gives it; `material` indexes `ObjMesh::materials`, None when the face
/// has no (known) material.
#[derive(Clone, Copy, Debug)]
pub struct ObjTriangle {
    pub positions: [Vec3; 3],
    pub normals: [Vec3; 3],
    pub material: Option<u32>,
    /// `vt` per corner; zero where the face has none.
    pub uvs: [Vec2; 3],
}

#[derive(Debug)]
pub struct ObjMesh {
    pub triangles: Vec<ObjTriangle>,
    /// Materials of every `mtllib`, in file order.
    pub materials: Vec<Material>,
    /// The MTL file (as messages name it) of each material.
    pub material_files: Vec<String>,
    /// Bytes of each MTL file in `mtllib` order, then of each texture (for the content hash).
    pub mtl_bytes: Vec<Vec<u8>>,
    /// The albedo textures the materials' `albedo_texture` index, one per distinct file and
    /// wrap.
    pub textures: Vec<Texture>,
    pub warnings: Vec<String>,
}

/// The value of `check`'s sentinel texture coordinate (a corner without `vt`), which no kept
/// coordinate reaches: those are below UV_LIMIT in magnitude.
const NO_UV: f32 = 3e38;
const UV_LIMIT: f32 = 1e30;

/// Reads an MTL file named by an OBJ: (name as written after `mtllib`, what referenced it)
/// -> (the name to use for it in messages, its bytes).
pub type MtlReader<'a> = dyn FnMut(&str, &str) -> Result<(String, Vec<u8>), SceneError> + 'a;

/// Materials for an OBJ that has none of its own: the MTL file (its name as `read_mtl` takes
/// it) and each group's material.
pub struct GroupMaterials<'a> {
    pub mtl: &'a str,
    /// Group name to material name; `"*"`: the groups not named.
    pub groups: &'a std::collections::BTreeMap<String, String>,
    /// Where the mapping was given, for messages ("scene.toml: mesh[0].groups").
    pub given_in: &'a str,
}

/// Loads the OBJ text `text`; `file` names it in messages; `read_mtl` fetches its MTL files;
/// `groups` assigns materials to its groups (the OBJ's own `usemtl` lines still apply after
/// each group's first line).
pub fn load(
    file: &str,
    text: &str,
    read_mtl: &mut MtlReader,
    groups: Option<&GroupMaterials>,
) -> Result<ObjMesh, SceneError> {
    let checked = check(file, text, groups)?;
    let mut warnings = checked.warnings;

    let mut materials = Vec::new();
    let mut material_files = Vec::new();
    let mut mtl_bytes = Vec::new();
    let mut tobj_libraries = Vec::new();
    let mut textures: Vec<Texture> = Vec::new();
    let mut texture_bytes = Vec::new();
    let mut texture_index: std::collections::HashMap<(String, [Wrap; 2]), u32> = Default::default();
    for (line, name) in &checked.mtllibs {
        let (mtl_file, bytes) = read_mtl(
            name,
            &format!("referenced by {file} line {line}: mtllib {name}"),
        )?;
        let mtl::MtlFile {
            materials: mut parsed,
            albedo_maps,
        } = mtl::parse(&mtl_file, &String::from_utf8_lossy(&bytes))?;
        let mtl_dir = Path::new(name).parent().unwrap_or(Path::new(""));
        for map in albedo_maps {
            let m = &mut parsed[map.material];
            let field = format!("material `{}` map_Kd (line {})", m.name, map.line);
            if !map.ignored.is_empty() {
                warnings.push(format!(
                    "{mtl_file}: {field}: ignored {} (irad applies -clamp only)",
                    map.ignored.join(", ")
                ));
            }
            let rel = mtl_dir.join(&map.path);
            let rel_name = rel.to_string_lossy().into_owned();
            let wrap = [map.wrap; 2];
            let index = match texture_index.get(&(rel_name.clone(), wrap)) {
                Some(&k) => k,
                None => {
                    let (texture_file, image) = read_mtl(
                        &rel_name,
                        &format!(
                            "referenced by {mtl_file} line {}: map_Kd {}",
                            map.line, map.path
                        ),
                    )?;
                    let t = texture::decode(&image, Path::new(&texture_file), wrap).map_err(
                        |problem| SceneError::Invalid {
                            file: mtl_file.clone(),
                            field: field.clone(),
                            value: texture_file.clone(),
                            problem,
                        },
                    )?;
                    texture_bytes.push(image);
                    textures.push(t);
                    let k = textures.len() as u32 - 1;
                    texture_index.insert((rel_name, wrap), k);
                    k
                }
            };
            m.albedo_texture = Some(index);
        }
        let mut names = Vec::new();
        let mut library = Vec::new();
        for (i, m) in parsed.iter().enumerate() {
            names.push((m.name.clone(), i));
            library.push(tobj::Material {
                name: m.name.clone(),
                ..Default::default()
            });
        }
        tobj_libraries.push((library, names));
        material_files.extend(parsed.iter().map(|_| mtl_file.clone()));
        materials.extend(parsed);
        mtl_bytes.push(bytes);
    }
    let known: std::collections::HashSet<&str> =
        materials.iter().map(|m| m.name.as_str()).collect();
    let unknown: Vec<String> = checked
        .usemtl
        .iter()
        .filter(|(_, name)| !known.contains(name.as_str()))
        .map(|(line, name)| format!("`{name}` (line {line})"))
        .collect();
    if !unknown.is_empty() {
        warnings.push(format!(
            "{file}: usemtl names no material of its MTL files: {}",
            unknown.join(", ")
        ));
    }

    // tobj calls the loader once per mtllib line, in file order, as `check` listed them.
    let next_library = Cell::new(0usize);
    let options = tobj::LoadOptions {
        single_index: false,
        triangulate: true,
        ignore_points: true,
        ignore_lines: true,
    };
    let (models, _) = tobj::load_obj_buf(&mut checked.text.as_bytes(), &options, |_: &Path| {
        let k = next_library.get();
        next_library.set(k + 1);
        // Later duplicates win, as in tobj's own MTL loader.
        Ok(match tobj_libraries.get(k) {
            Some((library, names)) => (library.clone(), names.iter().cloned().collect()),
            None => Default::default(),
        })
    })
    .map_err(|e| SceneError::File {
        file: file.to_string(),
        message: format!("tobj could not load it: {e}"),
    })?;

    let mut triangles = Vec::new();
    let mut without_material = 0usize;
    let mut without_uvs = 0usize;
    for model in &models {
        let mesh = &model.mesh;
        let material = mesh
            .material_id
            .filter(|&id| id < materials.len())
            .map(|id| id as u32);
        let has_normals = mesh.normal_indices.len() == mesh.indices.len();
        let has_uvs = mesh.texcoord_indices.len() == mesh.indices.len();
        // None for a corner without `vt` (check's sentinel).
        let uv = |k: usize| {
            if !has_uvs {
                return None;
            }
            let i = mesh.texcoord_indices[k] as usize * 2;
            mesh.texcoords
                .get(i..i + 2)
                .map(Vec2::from_slice)
                .filter(|uv| uv.x.abs() < UV_LIMIT)
        };
        let textured = material.is_some_and(|m| materials[m as usize].albedo_texture.is_some());
        let position = |k: usize| {
            let i = mesh.indices[k] as usize * 3;
            Vec3::from_slice(&mesh.positions[i..i + 3])
        };
        let given_normal = |k: usize| {
            if !has_normals {
                return Vec3::ZERO;
            }
            let i = mesh.normal_indices[k] as usize * 3;
            mesh.normals
                .get(i..i + 3)
                .map_or(Vec3::ZERO, Vec3::from_slice)
        };
        for t in 0..mesh.indices.len() / 3 {
            let positions = [position(3 * t), position(3 * t + 1), position(3 * t + 2)];
            let geometric = geometric_normal(positions);
            let normals = [0, 1, 2].map(|c| {
                let n = given_normal(3 * t + c);
                if n.length_squared().is_normal() {
                    n.normalize()
                } else {
                    // length_squared overflowed (a component over ~1.8e19), is subnormal or
                    // zero, or NaN: f64 still normalizes the finite non-zero ones.
                    let d = n.as_dvec3();
                    let length = d.length();
                    if length > 0.0 && length.is_finite() {
                        (d / length).as_vec3()
                    } else {
                        geometric
                    }
                }
            });
            if material.is_none() {
                without_material += 1;
            }
            let uvs = [uv(3 * t), uv(3 * t + 1), uv(3 * t + 2)];
            if textured && uvs.contains(&None) {
                without_uvs += 1;
            }
            triangles.push(ObjTriangle {
                positions,
                normals,
                material,
                uvs: uvs.map(|uv| uv.unwrap_or(Vec2::ZERO)),
            });
        }
    }
    if without_material > 0 {
        warnings.push(format!(
            "{file}: {without_material} triangles have no material (no usemtl, or one naming no \
             material of its MTL files); they get the default material (Kd 0.5)"
        ));
    }
    if without_uvs > 0 {
        warnings.push(format!(
            "{file}: {without_uvs} triangles of textured materials lack texture coordinates at a \
             corner (no vt); such corners read the texture at (0, 0)"
        ));
    }
    mtl_bytes.extend(texture_bytes);
    Ok(ObjMesh {
        triangles,
        materials,
        material_files,
        mtl_bytes,
        textures,
        warnings,
    })
}

/// The unit geometric normal `normalize(cross(p1 - p0, p2 - p0))`, in f64 so that tiny or huge
/// triangles still get one; zero for a degenerate triangle.
pub fn geometric_normal(p: [Vec3; 3]) -> Vec3 {
    let [a, b, c] = p.map(|v| v.as_dvec3());
    let n = (b - a).cross(c - a);
    let len = n.length();
    if len > 0.0 && len.is_finite() {
        (n / len).as_vec3()
    } else {
        Vec3::ZERO
    }
}

/// The largest coordinate magnitude a vertex may have. Beyond it f32 arithmetic fails the
/// renderer: at 1e10 every image came out black (hit offsets and light pdfs out of range), at
/// 1e19 obvhs's CWBVH conversion panicked; scenes at 1e8 render (tests/scene_loading.rs).
pub const MAX_COORDINATE: f32 = 1e8;

/// Twice the area of a triangle, in f64.
pub fn double_area(p: [Vec3; 3]) -> f64 {
    let [a, b, c]: [DVec3; 3] = p.map(|v| v.as_dvec3());
    (b - a).cross(c - a).length()
}

/// The OBJ text checked line by line and rewritten for tobj.
struct Checked {
    text: String,
    /// (line, file name) of each `mtllib`, in order.
    mtllibs: Vec<(usize, String)>,
    /// (line, material name) of each `usemtl`.
    usemtl: Vec<(usize, String)>,
    warnings: Vec<String>,
}

fn check(file: &str, text: &str, groups: Option<&GroupMaterials>) -> Result<Checked, SceneError> {
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    // Normal 1 (1-based) is the zero sentinel for corners without `vn`.
    let mut out = String::with_capacity(text.len() + 16);
    out.push_str("vn 0 0 0\n");
    // Texture coordinate 1 is the sentinel for corners without `vt`: its value, which no
    // coordinate kept takes (`load` reads it as none; tobj renumbers coordinates per mesh, so
    // only a value marks it).
    out.push_str(&format!("vt {NO_UV} {NO_UV}\n"));
    let mut unusable_uvs = 0usize;
    let mut mtllibs = Vec::new();
    let mut usemtl = Vec::new();
    // The scene's MTL for the groups, before any line of the file (tobj needs a library
    // before the `usemtl` lines that use it).
    if let Some(g) = groups {
        mtllibs.push((0, g.mtl.to_string()));
        out.push_str(&format!("mtllib {}\n", g.mtl));
    }
    let (mut positions, mut texcoords, mut normals) = (0usize, 0usize, 0usize);
    let (mut small_faces, mut line_elements) = (0usize, 0usize);
    for (i, line) in text.lines().enumerate() {
        let n = i + 1;
        let error = |message: String| SceneError::Line {
            file: file.to_string(),
            line: n,
            message,
        };
        let mut words = line.split_whitespace();
        let key = words.next();
        let values: Vec<&str> = words.collect();
        let numbers = |what: &str| -> Result<Vec<f32>, SceneError> {
            values
                .iter()
                .map(|v| {
                    v.parse::<f32>()
                        .map_err(|_| error(format!("{what}: `{v}` is not a number")))
                })
                .collect()
        };
        match key {
            Some("v") => {
                let v = numbers("vertex position")?;
                let p = match v[..] {
                    [x, y, z] | [x, y, z, _, _, _] => [x, y, z],
                    [x, y, z, w] => {
                        if !(w.is_finite() && w != 0.0) {
                            return Err(error(format!(
                                "vertex weight w = {w} must be finite and non-zero"
                            )));
                        }
                        [x / w, y / w, z / w]
                    }
                    _ => {
                        return Err(error(format!(
                            "vertex position: expected x y z [w], found `{}`",
                            values.join(" ")
                        )))
                    }
                };
                if !p.iter().all(|x| x.is_finite()) {
                    return Err(error(format!("vertex position {} is not finite", fmt3(p))));
                }
                if p.iter().any(|x| x.abs() > MAX_COORDINATE) {
                    return Err(error(format!(
                        "vertex position {}: a coordinate's magnitude is over {MAX_COORDINATE:e}, \
                         the most irad's f32 rays and BVH handle (scale the scene down)",
                        fmt3(p)
                    )));
                }
                positions += 1;
                out.push_str(&format!("v {} {} {}", p[0], p[1], p[2]));
            }
            Some("vn") => {
                let v = numbers("vertex normal")?;
                let [x, y, z] = v[..] else {
                    return Err(error(format!(
                        "vertex normal: expected x y z, found `{}`",
                        values.join(" ")
                    )));
                };
                normals += 1;
                // Non-finite normals fall back to the geometric normal, as zero ones do.
                if [x, y, z].iter().all(|c| c.is_finite()) {
                    out.push_str(&format!("vn {x} {y} {z}"));
                } else {
                    out.push_str("vn 0 0 0");
                }
            }
            Some("vt") => {
                if values.is_empty() || values.iter().any(|v| v.parse::<f32>().is_err()) {
                    return Err(error(format!(
                        "texture coordinate: expected numbers, found `{}`",
                        values.join(" ")
                    )));
                }
                texcoords += 1;
                let u = values[0].parse::<f32>().unwrap_or(0.0);
                let v = values
                    .get(1)
                    .and_then(|v| v.parse::<f32>().ok())
                    .unwrap_or(0.0);
                if u.abs() < UV_LIMIT && v.abs() < UV_LIMIT {
                    out.push_str(&format!("vt {u} {v}"));
                } else {
                    unusable_uvs += 1;
                    out.push_str(&format!("vt {NO_UV} {NO_UV}"));
                }
            }
            Some("f") => {
                let mut corners = Vec::with_capacity(values.len());
                for corner in &values {
                    let parts: Vec<&str> = corner.split('/').collect();
                    if parts.len() > 3 || parts[0].is_empty() {
                        return Err(error(format!(
                            "face corner `{corner}` is not v, v/vt, v//vn or v/vt/vn"
                        )));
                    }
                    let index = |part: &str,
                                 what: &str,
                                 count: usize|
                     -> Result<usize, SceneError> {
                        let k: i64 = part.parse().map_err(|_| {
                            error(format!(
                                "face corner `{corner}`: {what} index `{part}` is not an integer"
                            ))
                        })?;
                        let resolved = if k > 0 { k - 1 } else { count as i64 + k };
                        if k == 0 || resolved < 0 || resolved >= count as i64 {
                            return Err(error(format!(
                                "face corner `{corner}`: {what} index {k} is out of range ({count} defined before this line)"
                            )));
                        }
                        Ok(resolved as usize)
                    };
                    let v = index(parts[0], "vertex", positions)?;
                    let vt = match parts.get(1).filter(|s| !s.is_empty()) {
                        Some(vt) => index(vt, "texture coordinate", texcoords)? + 2,
                        None => 1,
                    };
                    let vn = match parts.get(2).filter(|s| !s.is_empty()) {
                        Some(vn) => index(vn, "normal", normals)? + 2,
                        None => 1,
                    };
                    corners.push(format!("{}/{vt}/{vn}", v + 1));
                }
                if corners.len() < 3 {
                    small_faces += 1;
                } else {
                    out.push_str("f ");
                    out.push_str(&corners.join(" "));
                }
            }
            Some("l") => line_elements += 1,
            Some("mtllib") | Some("usemtl") => {
                let name = line.trim_start()[6..].trim();
                if name.is_empty() {
                    return Err(error(format!("{} without a name", key.unwrap())));
                }
                if key == Some("mtllib") {
                    mtllibs.push((n, name.to_string()));
                    out.push_str(&format!("mtllib {name}"));
                } else {
                    usemtl.push((n, name.to_string()));
                    out.push_str(&format!("usemtl {name}"));
                }
            }
            Some("g") if groups.is_some() => {
                let g = groups.expect("checked");
                let name = values.join(" ");
                let Some(material) = g.groups.get(&name).or_else(|| g.groups.get("*")) else {
                    return Err(error(format!(
                        "group `{name}` has no material in {} (name it there, or give \"*\" \
                         for the groups not named)",
                        g.given_in
                    )));
                };
                usemtl.push((n, material.clone()));
                out.push_str(&format!("usemtl {material}"));
            }
            Some("o") | Some("g") => out.push_str(line),
            // Everything else (comments, s, p, curves) is ignored by tobj and by irad.
            _ => {}
        }
        out.push('\n');
    }
    let mut warnings = Vec::new();
    if unusable_uvs > 0 {
        warnings.push(format!(
            "{file}: {unusable_uvs} texture coordinates not finite or beyond 1e30 read as none"
        ));
    }
    if small_faces > 0 {
        warnings.push(format!(
            "{file}: ignored {small_faces} faces with fewer than 3 vertices"
        ));
    }
    if line_elements > 0 {
        warnings.push(format!(
            "{file}: ignored {line_elements} line elements (l): they are not surfaces"
        ));
    }
    Ok(Checked {
        text: out,
        mtllibs,
        usemtl,
        warnings,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn no_mtl(_: &str, _: &str) -> Result<(String, Vec<u8>), SceneError> {
        panic!("no mtllib expected")
    }

    #[test]
    fn quads_are_triangulated_and_normals_resolved_per_corner() {
        let text = "v 0 0 0\nv 1 0 0\nv 1 0 -1\nv 0 0 -1\nvn 0 2 0\nvn nan 0 0\n\
                    f 1//1 2//2 3 4\n";
        let mesh = load("q.obj", text, &mut no_mtl, None).unwrap();
        assert_eq!(mesh.triangles.len(), 2);
        let t = mesh.triangles[0];
        assert_eq!(
            t.positions,
            [Vec3::ZERO, Vec3::X, Vec3::new(1.0, 0.0, -1.0)]
        );
        // Given (normalized), NaN -> geometric, missing -> geometric.
        assert_eq!(t.normals, [Vec3::Y; 3]);
        assert_eq!(t.material, None);
        assert!(mesh
            .warnings
            .iter()
            .any(|w| w.contains("2 triangles have no material")));
    }

    #[test]
    fn texture_coordinates_are_kept_per_corner() {
        let text = "v 0 0 0\nv 1 0 0\nv 1 0 -1\nv 0 0 -1\nvt 0.25 0.5\nvt 1 0 0\nvt -2 3\n\
                    f 1/1 2/2 3/3\nf 1/-3/ 3 4\n";
        let mesh = load("t.obj", text, &mut no_mtl, None).unwrap();
        assert_eq!(
            mesh.triangles[0].uvs,
            [Vec2::new(0.25, 0.5), Vec2::X, Vec2::new(-2.0, 3.0)]
        );
        // A corner without vt gets (0, 0).
        assert_eq!(
            mesh.triangles[1].uvs,
            [Vec2::new(0.25, 0.5), Vec2::ZERO, Vec2::ZERO]
        );
        // A coordinate past 1e30 or not finite is read as none, with a warning.
        let mesh = load(
            "t.obj",
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 inf\nvt 0.5 0.5\nf 1/1 2/2 3/2\n",
            &mut no_mtl,
            None,
        )
        .unwrap();
        assert_eq!(mesh.triangles[0].uvs[0], Vec2::ZERO);
        assert_eq!(mesh.triangles[0].uvs[1], Vec2::splat(0.5));
        assert!(
            mesh.warnings
                .iter()
                .any(|w| w.contains("1 texture coordinates not finite or beyond 1e30")),
            "{:?}",
            mesh.warnings
        );
    }

    #[test]
    fn relative_indices_and_w_are_resolved() {
        let text = "v 0 0 0 2\nv 2 0 0\nv 0 4 0 2\nf -3 -2 -1\n";
        let mesh = load("r.obj", text, &mut no_mtl, None).unwrap();
        assert_eq!(
            mesh.triangles[0].positions,
            [
                Vec3::ZERO,
                Vec3::new(2.0, 0.0, 0.0),
                Vec3::new(0.0, 2.0, 0.0)
            ]
        );
        assert_eq!(mesh.triangles[0].normals, [Vec3::Z; 3]);
    }

    #[test]
    fn bad_lines_are_named() {
        let cases = [
            (
                "v 0 0 0\nv 1 nan 0\n",
                "b.obj line 2: vertex position [1, NaN, 0] is not finite",
            ),
            (
                "v 0 0 0\nv 1 x 0\n",
                "b.obj line 2: vertex position: `x` is not a number",
            ),
            (
                "v 0 0 0\nf 1 2 3\n",
                "b.obj line 2: face corner `2`: vertex index 2 is out of range",
            ),
            (
                "v 0 0 0\nf 1//-9 1 1\n",
                "b.obj line 2: face corner `1//-9`: normal index -9",
            ),
            ("usemtl\n", "b.obj line 1: usemtl without a name"),
        ];
        for (text, expected) in cases {
            let m = load("b.obj", text, &mut no_mtl, None)
                .unwrap_err()
                .to_string();
            assert!(m.contains(expected), "{m}");
        }
    }

    #[test]
    fn materials_come_from_the_mtllib_in_order() {
        let text =
            "mtllib a.mtl\nmtllib b.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl second\nf 1 2 3\n\
                    usemtl first\nf 1 2 3\nusemtl nothing\nf 1 2 3\n";
        let mut read = |name: &str, by: &str| -> Result<(String, Vec<u8>), SceneError> {
            assert!(by.contains("line 1") || by.contains("line 2"), "{by}");
            let body = if name == "a.mtl" {
                "newmtl first\nKd 0.1\n"
            } else {
                "newmtl second\nKd 0.2\n"
            };
            Ok((name.to_string(), body.as_bytes().to_vec()))
        };
        let mesh = load("m.obj", text, &mut read, None).unwrap();
        let names: Vec<_> = mesh
            .triangles
            .iter()
            .map(|t| t.material.map(|m| mesh.materials[m as usize].name.as_str()))
            .collect();
        assert_eq!(names, [Some("second"), Some("first"), None]);
        assert!(
            mesh.warnings
                .iter()
                .any(|w| w.contains("`nothing` (line 10)")),
            "{:?}",
            mesh.warnings
        );
    }
}
