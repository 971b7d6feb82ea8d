//! Mitsuba shapes as irad's triangles: PLY (binary little- or big-endian, or ASCII) and OBJ
//! meshes, and the primitives tessellated in their local space (rectangle [-1, 1]^2 at z = 0
//! facing +z, cube [-1, 1]^3 facing out, disk of radius 1 facing +z, sphere of `radius` about
//! `center`), then taken to the world by `to_world`.

use glam::{DMat4, DVec3, Vec3};

/// A triangle before its material: counter-clockwise corners and their shading normals.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RawTriangle {
    pub positions: [Vec3; 3],
    pub normals: [Vec3; 3],
}

/// Segments around a disk's rim and a sphere's equator (`<integer name="tessellation">`
/// overrides it per shape).
pub const DEFAULT_SEGMENTS: u32 = 64;

/// Local-space triangles (f64) and optional per-corner normals.
pub type Local = Vec<([DVec3; 3], Option<[DVec3; 3]>)>;

pub fn rectangle() -> Local {
    let p = [
        DVec3::new(-1.0, -1.0, 0.0),
        DVec3::new(1.0, -1.0, 0.0),
        DVec3::new(1.0, 1.0, 0.0),
        DVec3::new(-1.0, 1.0, 0.0),
    ];
    vec![([p[0], p[1], p[2]], None), ([p[0], p[2], p[3]], None)]
}

pub fn cube() -> Local {
    let mut out = Vec::new();
    // Each face: its normal axis and sign; corners counter-clockwise seen from outside.
    for axis in 0..3 {
        for sign in [-1.0, 1.0] {
            let n = DVec3::from_array({
                let mut a = [0.0; 3];
                a[axis] = sign;
                a
            });
            let u = DVec3::from_array({
                let mut a = [0.0; 3];
                a[(axis + 1) % 3] = 1.0;
                a
            });
            let v = n.cross(u);
            let c = |a: f64, b: f64| n + a * u + b * v;
            let q = [c(-1.0, -1.0), c(1.0, -1.0), c(1.0, 1.0), c(-1.0, 1.0)];
            out.push(([q[0], q[1], q[2]], None));
            out.push(([q[0], q[2], q[3]], None));
        }
    }
    out
}

pub fn disk(segments: u32) -> Local {
    let k = segments.max(3);
    (0..k)
        .map(|i| {
            let a = |j: u32| {
                let t = std::f64::consts::TAU * j as f64 / k as f64;
                DVec3::new(t.cos(), t.sin(), 0.0)
            };
            ([DVec3::ZERO, a(i), a(i + 1)], None)
        })
        .collect()
}

/// A UV sphere of `segments` around and `segments / 2` rings, with the sphere's normals.
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
    let mut out = Vec::new();
    for j in 0..rings {
        for i in 0..k {
            let (a, b, c, d) = (at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1));
            let mut push = |t: [DVec3; 3]| {
                let p = t.map(|n| center + radius * n);
                if (p[1] - p[0]).cross(p[2] - p[0]).length_squared() > 0.0 {
                    out.push((p, Some(t)));
                }
            };
            // Counter-clockwise seen from outside.
            push([a, c, b]);
            push([a, d, c]);
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
        .map(|(p, n)| {
            let mut positions = p.map(|v| m.transform_point3(v));
            let mut normals = n.map(|n| match identity {
                true => n,
                false => n.map(|v| normal_matrix.transform_vector3(v).normalize_or_zero()),
            });
            if mirror != flip {
                positions.swap(1, 2);
                if let Some(n) = normals.as_mut() {
                    n.swap(1, 2);
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
            }
        })
        .collect()
}

/// A PLY element's property: name, type, and for a list the type of its count.
type Property = (String, String, Option<String>);

/// A PLY file's triangles (polygons fanned), with its vertex normals; where it has none,
/// area-weighted vertex normals over the faces that share each vertex (Mitsuba's, unless the
/// shape asks for face normals).
pub fn read_ply(bytes: &[u8]) -> Result<Local, String> {
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
    let mut faces: Vec<Vec<usize>> = Vec::new();
    for (name, count, props) in &elements {
        let index = |n: &str| props.iter().position(|p| p.0 == n);
        let (x, y, z) = (index("x"), index("y"), index("z"));
        let (nx, ny, nz) = (index("nx"), index("ny"), index("nz"));
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
    Ok(triangles
        .into_iter()
        .map(|t| (t.map(|i| positions[i]), Some(t.map(|i| normals[i]))))
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
/// Mitsuba would smooth a mesh without normals); its materials are not read (the shape's BSDF
/// applies).
pub fn read_obj(display: &str, text: &str) -> Result<Local, crate::scene::SceneError> {
    let mut no_mtl = |_: &str, _: &str| Ok((String::new(), Vec::new()));
    let mesh = crate::scene::obj::load(display, text, &mut no_mtl, None)?;
    Ok(mesh
        .triangles
        .into_iter()
        .map(|t| {
            (
                t.positions.map(|p| p.as_dvec3()),
                Some(t.normals.map(|n| n.as_dvec3())),
            )
        })
        .collect())
}
