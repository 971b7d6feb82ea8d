//! Mitsuba shapes as irad's triangles: PLY (binary little- or big-endian, or ASCII) and OBJ
//! meshes, and the primitives tessellated in their local space (rectangle [-1, 1]^2 at z = 0
//! facing +z, cube [-1, 1]^3 facing out, disk of radius 1 facing +z, sphere of `radius` about
//! `center`), then taken to the world by `to_world`.
//!
//! Texture coordinates are kept in irad's convention (v up; irad's v is 1 - Mitsuba's, whose
//! bitmap lookup has v = 0 at the image's top, textures.rs): PLY `u v` (or `texture_u
//! texture_v`, `s t`) with `flip_tex_coords` (false by default, as Mitsuba's ply plugin), OBJ
//! `vt` (Mitsuba's obj plugin flips them by default, which is irad's convention as written),
//! and the primitives' parameterizations as Mitsuba 3 defines them (src/shapes/*.cpp):
//! rectangle u = (x + 1) / 2, v = (y + 1) / 2; cube each face [0, 1]^2 as cube.cpp's table;
//! disk u = r, v = phi / 2 pi; sphere u = phi / 2 pi, v = theta / pi (phi from +x towards +y,
//! theta from +z), each corner of the tessellation at its own values.

use glam::{DMat4, DVec3, Vec2, Vec3};

/// A triangle before its material: counter-clockwise corners, their shading normals and
/// texture coordinates (irad's convention; None where the shape has none).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RawTriangle {
    pub positions: [Vec3; 3],
    pub normals: [Vec3; 3],
    pub uvs: Option<[Vec2; 3]>,
}

/// Segments around a disk's rim and a sphere's equator (`<integer name="tessellation">`
/// overrides it per shape).
pub const DEFAULT_SEGMENTS: u32 = 64;

/// A local-space triangle (f64), its optional per-corner normals and texture coordinates
/// (irad's convention).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LocalTriangle {
    pub positions: [DVec3; 3],
    pub normals: Option<[DVec3; 3]>,
    pub uvs: Option<[Vec2; 3]>,
}

pub type Local = Vec<LocalTriangle>;

/// Mitsuba's (u, v) (v down) as irad's (v up).
fn from_mitsuba(u: f64, v: f64) -> Vec2 {
    Vec2::new(u as f32, (1.0 - v) as f32)
}

fn flat(positions: [DVec3; 3], uvs: [Vec2; 3]) -> LocalTriangle {
    LocalTriangle {
        positions,
        normals: None,
        uvs: Some(uvs),
    }
}

/// [-1, 1]^2 at z = 0 facing +z; Mitsuba's uv ((x + 1) / 2, (y + 1) / 2), so the image's
/// top-left corner is at (-1, -1).
pub fn rectangle() -> Local {
    let corner = |x: f64, y: f64| {
        (
            DVec3::new(x, y, 0.0),
            from_mitsuba((x + 1.0) / 2.0, (y + 1.0) / 2.0),
        )
    };
    let q = [
        corner(-1.0, -1.0),
        corner(1.0, -1.0),
        corner(1.0, 1.0),
        corner(-1.0, 1.0),
    ];
    [[0, 1, 2], [0, 2, 3]]
        .iter()
        .map(|t| flat(t.map(|i| q[i].0), t.map(|i| q[i].1)))
        .collect()
}

/// [-1, 1]^3 facing out: Mitsuba 3's cube.cpp, its 24 vertices (each face its own four, uv
/// (0, 1), (1, 1), (1, 0), (0, 0)) and 12 triangles, counter-clockwise seen from outside.
pub fn cube() -> Local {
    const VERTICES: [[f64; 3]; 24] = [
        [1.0, -1.0, -1.0],
        [1.0, -1.0, 1.0],
        [-1.0, -1.0, 1.0],
        [-1.0, -1.0, -1.0],
        [1.0, 1.0, -1.0],
        [-1.0, 1.0, -1.0],
        [-1.0, 1.0, 1.0],
        [1.0, 1.0, 1.0],
        [1.0, -1.0, -1.0],
        [1.0, 1.0, -1.0],
        [1.0, 1.0, 1.0],
        [1.0, -1.0, 1.0],
        [1.0, -1.0, 1.0],
        [1.0, 1.0, 1.0],
        [-1.0, 1.0, 1.0],
        [-1.0, -1.0, 1.0],
        [-1.0, -1.0, 1.0],
        [-1.0, 1.0, 1.0],
        [-1.0, 1.0, -1.0],
        [-1.0, -1.0, -1.0],
        [1.0, 1.0, -1.0],
        [1.0, -1.0, -1.0],
        [-1.0, -1.0, -1.0],
        [-1.0, 1.0, -1.0],
    ];
    const UVS: [[f64; 2]; 4] = [[0.0, 1.0], [1.0, 1.0], [1.0, 0.0], [0.0, 0.0]];
    let mut out = Vec::new();
    for face in 0..6 {
        let v = 4 * face;
        for t in [[v, v + 1, v + 2], [v + 3, v, v + 2]] {
            out.push(flat(
                t.map(|i| DVec3::from_array(VERTICES[i])),
                t.map(|i| from_mitsuba(UVS[i % 4][0], UVS[i % 4][1])),
            ));
        }
    }
    out
}

/// A disk of radius 1 facing +z, fanned into `segments`; Mitsuba's uv (r, phi / 2 pi), the
/// centre of each triangle at its middle angle.
pub fn disk(segments: u32) -> Local {
    let k = segments.max(3);
    (0..k)
        .map(|i| {
            let a = |j: u32| {
                let t = std::f64::consts::TAU * j as f64 / k as f64;
                DVec3::new(t.cos(), t.sin(), 0.0)
            };
            let v = |j: f64| j / k as f64;
            flat(
                [DVec3::ZERO, a(i), a(i + 1)],
                [
                    from_mitsuba(0.0, v(i as f64 + 0.5)),
                    from_mitsuba(1.0, v(i as f64)),
                    from_mitsuba(1.0, v(i as f64 + 1.0)),
                ],
            )
        })
        .collect()
}

/// A UV sphere of `segments` around and `segments / 2` rings, with the sphere's normals and
/// Mitsuba's uv (phi / 2 pi, theta / pi); a pole corner at its triangle's middle phi.
pub fn sphere(center: DVec3, radius: f64, segments: u32) -> Local {
    let (k, rings) = (segments.max(4), (segments / 2).max(2));
    let at = |i: u32, j: u32| {
        let phi = std::f64::consts::TAU * i as f64 / k as f64;
        let theta = std::f64::consts::PI * j as f64 / rings as f64;
        DVec3::new(
            theta.sin() * phi.cos(),
            theta.sin() * phi.sin(),
            theta.cos(),
        )
    };
    let uv = |i: u32, j: u32, column: u32| {
        let u = if j == 0 || j == rings {
            (column as f64 + 0.5) / k as f64
        } else {
            i as f64 / k as f64
        };
        from_mitsuba(u, j as f64 / rings as f64)
    };
    let mut out = Vec::new();
    for j in 0..rings {
        for i in 0..k {
            let corners = [(i, j), (i + 1, j), (i + 1, j + 1), (i, j + 1)];
            let mut push = |t: [usize; 3]| {
                let n = t.map(|c| at(corners[c].0, corners[c].1));
                let p = n.map(|n| center + radius * n);
                if (p[1] - p[0]).cross(p[2] - p[0]).length_squared() > 0.0 {
                    out.push(LocalTriangle {
                        positions: p,
                        normals: Some(n),
                        uvs: Some(t.map(|c| uv(corners[c].0, corners[c].1, i))),
                    });
                }
            };
            // Counter-clockwise seen from outside.
            push([0, 2, 1]);
            push([0, 3, 2]);
        }
    }
    out
}

/// Local triangles to the world: positions by `m`, normals by its inverse transpose;
/// `flip` reverses the winding and the given normals. A mirroring `m` (det < 0) has its
/// winding undone, as Mitsuba does; triangles without normals get the final face normal.
pub fn to_world(local: Local, m: DMat4, flip: bool) -> Vec<RawTriangle> {
    // The identity keeps every bit (a mesh irad exported reads back as it was).
    let identity = m == DMat4::IDENTITY;
    let normal_matrix = m.inverse().transpose();
    let mirror = m.determinant() < 0.0;
    local
        .into_iter()
        .map(|t| {
            let mut positions = t.positions.map(|v| m.transform_point3(v));
            let mut normals = t.normals.map(|n| match identity {
                true => n,
                false => n.map(|v| normal_matrix.transform_vector3(v).normalize_or_zero()),
            });
            let mut uvs = t.uvs;
            if mirror != flip {
                positions.swap(1, 2);
                if let Some(n) = normals.as_mut() {
                    n.swap(1, 2);
                }
                if let Some(uv) = uvs.as_mut() {
                    uv.swap(1, 2);
                }
            }
            if flip {
                normals = normals.map(|n| n.map(|v| -v));
            }
            let face = (positions[1] - positions[0])
                .cross(positions[2] - positions[0])
                .normalize_or_zero();
            RawTriangle {
                positions: positions.map(|v| v.as_vec3()),
                normals: normals.unwrap_or([face; 3]).map(|v| v.as_vec3()),
                uvs,
            }
        })
        .collect()
}

/// A PLY element's property: name, type, and for a list the type of its count.
type Property = (String, String, Option<String>);

/// A PLY file's triangles (polygons fanned), with its vertex normals; where it has none,
/// area-weighted vertex normals over the faces that share each vertex (Mitsuba's, unless the
/// shape asks for face normals). Texture coordinates from `u v`, else `texture_u texture_v`,
/// else `s t`, in Mitsuba's convention, or irad's with `flip_tex_coords`.
pub fn read_ply(bytes: &[u8], flip_tex_coords: bool) -> Result<Local, String> {
    // The header: lines from the start up to `end_header`.
    let mut at = 0;
    let mut lines = Vec::new();
    loop {
        let end = bytes[at..]
            .iter()
            .position(|&b| b == b'\n')
            .ok_or("no end_header line")?;
        let line = std::str::from_utf8(&bytes[at..at + end])
            .map_err(|_| "a header line that is not text")?
            .trim_end_matches('\r');
        at += end + 1;
        if line == "end_header" {
            break;
        }
        lines.push(line);
    }
    if lines.first() != Some(&"ply") {
        return Err("not a PLY file (its first line is not `ply`)".into());
    }
    let body = &bytes[at..];
    let mut format = "";
    // Elements: (name, count, properties).
    let mut elements: Vec<(String, usize, Vec<Property>)> = Vec::new();
    for line in &lines {
        let w: Vec<&str> = line.split_whitespace().collect();
        match w.as_slice() {
            ["format", f, ..] => format = f,
            ["element", name, count] => elements.push((
                name.to_string(),
                count
                    .parse()
                    .map_err(|_| format!("element count `{count}`"))?,
                Vec::new(),
            )),
            ["property", "list", count, item, name] => elements
                .last_mut()
                .ok_or("a property before any element")?
                .2
                .push((name.to_string(), item.to_string(), Some(count.to_string()))),
            ["property", ty, name] => elements
                .last_mut()
                .ok_or("a property before any element")?
                .2
                .push((name.to_string(), ty.to_string(), None)),
            _ => {}
        }
    }
    // Each element's items take at least a byte (a character in ASCII): a count past the
    // body's size is a broken header, not an allocation to try.
    for (name, count, props) in &elements {
        if *count > 0 && (props.is_empty() || *count > body.len()) {
            return Err(format!(
                "element `{name}`: {count} items do not fit the file"
            ));
        }
    }
    let text;
    let mut reader = if format == "ascii" {
        text = std::str::from_utf8(body).map_err(|_| "an ASCII body that is not text")?;
        Reader::ascii(text)
    } else {
        Reader::binary(body, format)?
    };
    let mut positions: Vec<DVec3> = Vec::new();
    let mut normals: Vec<DVec3> = Vec::new();
    let mut uvs: Vec<Vec2> = Vec::new();
    let mut faces: Vec<Vec<usize>> = Vec::new();
    for (name, count, props) in &elements {
        let index = |n: &str| props.iter().position(|p| p.0 == n);
        let (x, y, z) = (index("x"), index("y"), index("z"));
        let (nx, ny, nz) = (index("nx"), index("ny"), index("nz"));
        let uv = [("u", "v"), ("texture_u", "texture_v"), ("s", "t")]
            .iter()
            .find_map(|(u, v)| index(u).zip(index(v)));
        let list = index("vertex_indices").or_else(|| index("vertex_index"));
        let mut values: Vec<Vec<f64>> = vec![Vec::new(); props.len()];
        for _ in 0..*count {
            for (k, (_, ty, list)) in props.iter().enumerate() {
                values[k].clear();
                match list {
                    Some(count_type) => {
                        let n = reader.scalar(count_type)?;
                        if !(n >= 0.0 && n.fract() == 0.0 && (n as usize) <= body.len()) {
                            return Err(format!("a list of {n} items"));
                        }
                        for _ in 0..n as usize {
                            values[k].push(reader.scalar(ty)?);
                        }
                    }
                    None => values[k].push(reader.scalar(ty)?),
                }
            }
            let one = |k: usize| {
                values[k]
                    .first()
                    .copied()
                    .ok_or("an empty list as a number")
            };
            match name.as_str() {
                "vertex" => {
                    let (Some(x), Some(y), Some(z)) = (x, y, z) else {
                        return Err("vertices without x, y and z".into());
                    };
                    positions.push(DVec3::new(one(x)?, one(y)?, one(z)?));
                    if let (Some(a), Some(b), Some(c)) = (nx, ny, nz) {
                        normals.push(DVec3::new(one(a)?, one(b)?, one(c)?));
                    }
                    if let Some((u, v)) = uv {
                        // Mitsuba reads them as f32 and flips in f32: 1 - v.
                        let (u, v) = (one(u)? as f32, one(v)? as f32);
                        uvs.push(if flip_tex_coords {
                            Vec2::new(u, v)
                        } else {
                            Vec2::new(u, 1.0 - v)
                        });
                    }
                }
                "face" => {
                    let list = list.ok_or("faces without vertex_indices")?;
                    let mut face = Vec::with_capacity(values[list].len());
                    for &v in &values[list] {
                        if !(v >= 0.0 && v.fract() == 0.0) {
                            return Err(format!("a face names vertex {v}"));
                        }
                        face.push(v as usize);
                    }
                    faces.push(face);
                }
                _ => {}
            }
        }
    }
    let mut triangles: Vec<[usize; 3]> = Vec::with_capacity(faces.len());
    for face in faces {
        if let Some(&bad) = face.iter().find(|&&i| i >= positions.len()) {
            return Err(format!("a face names vertex {bad} of {}", positions.len()));
        }
        for k in 1..face.len().saturating_sub(1) {
            triangles.push([face[0], face[k], face[k + 1]]);
        }
    }
    if normals.len() != positions.len() {
        // Area-weighted vertex normals (the cross product's length is twice the area).
        normals = vec![DVec3::ZERO; positions.len()];
        for t in &triangles {
            let p = t.map(|i| positions[i]);
            let n = (p[1] - p[0]).cross(p[2] - p[0]);
            for &i in t {
                normals[i] += n;
            }
        }
    }
    let has_uvs = uvs.len() == positions.len();
    Ok(triangles
        .into_iter()
        .map(|t| LocalTriangle {
            positions: t.map(|i| positions[i]),
            normals: Some(t.map(|i| normals[i])),
            uvs: has_uvs.then(|| t.map(|i| uvs[i])),
        })
        .collect())
}

/// Reads PLY scalars from the body in its format.
struct Reader<'a> {
    bytes: &'a [u8],
    at: usize,
    ascii: Option<std::str::SplitWhitespace<'a>>,
    big_endian: bool,
}

impl<'a> Reader<'a> {
    fn ascii(text: &'a str) -> Self {
        Reader {
            bytes: &[],
            at: 0,
            ascii: Some(text.split_whitespace()),
            big_endian: false,
        }
    }

    fn binary(bytes: &'a [u8], format: &str) -> Result<Self, String> {
        match format {
            "binary_little_endian" | "binary_big_endian" => Ok(Reader {
                bytes,
                at: 0,
                ascii: None,
                big_endian: format == "binary_big_endian",
            }),
            other => Err(format!("format `{other}`")),
        }
    }

    fn take<const N: usize>(&mut self) -> Result<[u8; N], String> {
        let b = self
            .bytes
            .get(self.at..self.at + N)
            .ok_or("the file ends before its elements do")?;
        self.at += N;
        let mut a = [0u8; N];
        a.copy_from_slice(b);
        if self.big_endian {
            a.reverse();
        }
        Ok(a)
    }

    fn scalar(&mut self, ty: &str) -> Result<f64, String> {
        if let Some(words) = &mut self.ascii {
            let w = words.next().ok_or("the file ends before its elements do")?;
            return w.parse().map_err(|_| format!("`{w}` is not a number"));
        }
        Ok(match ty {
            "char" | "int8" => i8::from_le_bytes(self.take()?) as f64,
            "uchar" | "uint8" => u8::from_le_bytes(self.take()?) as f64,
            "short" | "int16" => i16::from_le_bytes(self.take()?) as f64,
            "ushort" | "uint16" => u16::from_le_bytes(self.take()?) as f64,
            "int" | "int32" => i32::from_le_bytes(self.take()?) as f64,
            "uint" | "uint32" => u32::from_le_bytes(self.take()?) as f64,
            "float" | "float32" => f32::from_le_bytes(self.take()?) as f64,
            "double" | "float64" => f64::from_le_bytes(self.take()?),
            other => return Err(format!("property type `{other}`")),
        })
    }
}

/// An OBJ file's triangles through irad's own OBJ reader (src/scene/obj.rs: every line
/// checked, coordinates bounded), its `vn` normals where given (the face normal elsewhere:
/// Mitsuba would smooth a mesh without normals), its `vt` (v up, irad's convention, which
/// Mitsuba's default `flip_tex_coords` true also reads; false: v down); none where the file
/// has no `vt` at all. Its materials are not read (the shape's BSDF applies).
pub fn read_obj(
    display: &str,
    text: &str,
    flip_tex_coords: bool,
) -> Result<Local, crate::scene::SceneError> {
    let mut no_mtl = |_: &str, _: &str| Ok((String::new(), Vec::new()));
    let mesh = crate::scene::obj::load(display, text, &mut no_mtl, None)?;
    let has_uvs = mesh
        .triangles
        .iter()
        .any(|t| t.uvs.iter().any(|&uv| uv != Vec2::ZERO));
    Ok(mesh
        .triangles
        .into_iter()
        .map(|t| LocalTriangle {
            positions: t.positions.map(|p| p.as_dvec3()),
            normals: Some(t.normals.map(|n| n.as_dvec3())),
            uvs: has_uvs.then(|| {
                t.uvs.map(|uv| match flip_tex_coords {
                    true => uv,
                    false => Vec2::new(uv.x, 1.0 - uv.y),
                })
            }),
        })
        .collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Mitsuba's (u, v) at irad's uv.
    fn mitsuba(uv: Vec2) -> (f64, f64) {
        (uv.x as f64, 1.0 - uv.y as f64)
    }

    #[test]
    fn primitives_carry_mitsubas_parameterization() {
        // Rectangle: Mitsuba's uv = ((x + 1) / 2, (y + 1) / 2) at every corner.
        for t in rectangle() {
            for (p, uv) in t.positions.iter().zip(t.uvs.unwrap()) {
                assert_eq!(mitsuba(uv), ((p.x + 1.0) / 2.0, (p.y + 1.0) / 2.0));
            }
        }
        // Cube: outward, counter-clockwise, each face [0, 1]^2 (area 1/2 per triangle).
        let cube = cube();
        assert_eq!(cube.len(), 12);
        for t in &cube {
            let p = t.positions;
            let n = (p[1] - p[0]).cross(p[2] - p[0]);
            assert!(n.dot(p[0] + p[1] + p[2]) > 0.0, "{p:?} faces in");
            let uv = t.uvs.unwrap().map(|u| u.as_dvec2());
            assert_eq!((uv[1] - uv[0]).perp_dot(uv[2] - uv[0]).abs(), 1.0);
        }
        // Disk: rim corners at (1, phi / 2 pi), the centre at r = 0.
        for t in disk(8) {
            let uv = t.uvs.unwrap();
            assert_eq!(mitsuba(uv[0]).0, 0.0);
            for (p, uv) in t.positions.iter().zip(uv).skip(1) {
                let phi = p.y.atan2(p.x).rem_euclid(std::f64::consts::TAU);
                let (u, v) = mitsuba(uv);
                assert_eq!(u, 1.0);
                let v_phi = phi / std::f64::consts::TAU;
                assert!((v - v_phi).abs() < 1e-6 || (v - v_phi - 1.0).abs() < 1e-6);
            }
        }
        // Sphere: (phi / 2 pi, theta / pi) at every corner off the poles (u = 1 on the seam).
        let (center, radius) = (DVec3::new(1.0, 2.0, 3.0), 0.5);
        for t in sphere(center, radius, 16) {
            for (p, uv) in t.positions.iter().zip(t.uvs.unwrap()) {
                let d = (*p - center) / radius;
                let (u, v) = mitsuba(uv);
                let theta = d.z.clamp(-1.0, 1.0).acos();
                assert!(
                    (v - theta / std::f64::consts::PI).abs() < 1e-6,
                    "{v} {theta}"
                );
                if d.z.abs() < 1.0 - 1e-9 {
                    let phi = d.y.atan2(d.x).rem_euclid(std::f64::consts::TAU);
                    let u_phi = phi / std::f64::consts::TAU;
                    assert!(
                        (u - u_phi).abs() < 1e-6 || (u - u_phi - 1.0).abs() < 1e-6,
                        "{u} {u_phi}"
                    );
                }
            }
        }
    }

    #[test]
    fn ply_texture_coordinates_in_every_spelling() {
        let ply = |u: &str, v: &str| {
            format!(
                "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n\
                 property float z\nproperty float {u}\nproperty float {v}\nelement face 1\n\
                 property list uchar int vertex_indices\nend_header\n\
                 0 0 0 0.25 0.125\n1 0 0 1 0\n0 1 0 0 1\n3 0 1 2\n"
            )
        };
        for (u, v) in [("u", "v"), ("texture_u", "texture_v"), ("s", "t")] {
            let t = read_ply(ply(u, v).as_bytes(), false).unwrap();
            assert_eq!(t[0].uvs.unwrap()[0], Vec2::new(0.25, 0.875), "{u} {v}");
            let t = read_ply(ply(u, v).as_bytes(), true).unwrap();
            assert_eq!(t[0].uvs.unwrap()[0], Vec2::new(0.25, 0.125), "{u} {v}");
        }
        let t = read_ply(ply("q", "r").as_bytes(), false).unwrap();
        assert_eq!(t[0].uvs, None);
    }
}
