//! Binary little-endian PLY triangle meshes, written by hand: every triangle its own three
//! vertices (`x y z nx ny nz`, float32, then `u v` for a mesh written with texture
//! coordinates) and one face (`vertex_indices`, a uchar count of 3 and three uint32 indices).
//! Vertices are not shared, so a corner keeps its own normal and a reader that averages normals
//! over shared vertices (Mitsuba does when a mesh has none) has nothing to average.

use std::io::Write;
use std::path::Path;

use glam::{Vec2, Vec3};

/// One triangle to write: counter-clockwise corners, their unit normals and texture
/// coordinates (written only for a mesh with `uvs`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PlyTriangle {
    pub positions: [Vec3; 3],
    pub normals: [Vec3; 3],
    pub uvs: [Vec2; 3],
}

/// Most triangles one file can index with uint32 vertex indices.
pub const MAX_TRIANGLES: usize = (u32::MAX / 3) as usize;

/// The header for `triangles` triangles, with `u v` properties when `uvs`; `comment` (one
/// line, control characters replaced by spaces) says what the mesh is.
pub fn header(comment: &str, triangles: usize, uvs: bool) -> String {
    let comment: String = comment
        .chars()
        .map(|c| if c.is_control() { ' ' } else { c })
        .collect();
    format!(
        "ply\nformat binary_little_endian 1.0\ncomment {comment}\nelement vertex {}\n\
         property float x\nproperty float y\nproperty float z\n\
         property float nx\nproperty float ny\nproperty float nz\n{}\
         element face {triangles}\nproperty list uchar uint vertex_indices\nend_header\n",
        3 * triangles,
        if uvs {
            "property float u\nproperty float v\n"
        } else {
            ""
        }
    )
}

/// Writes `triangles` to `path`, with their texture coordinates when `uvs` (more than
/// `MAX_TRIANGLES` is an `InvalidInput` error).
pub fn write(
    path: &Path,
    comment: &str,
    triangles: &[PlyTriangle],
    uvs: bool,
) -> std::io::Result<()> {
    if triangles.len() > MAX_TRIANGLES {
        return Err(std::io::Error::new(
            std::io::ErrorKind::InvalidInput,
            format!(
                "{} triangles: a PLY file with uint32 indices holds at most {MAX_TRIANGLES}",
                triangles.len()
            ),
        ));
    }
    let mut bytes = header(comment, triangles.len(), uvs).into_bytes();
    let vertex = if uvs { 32 } else { 24 };
    bytes.reserve(triangles.len() * (3 * vertex + 13));
    for t in triangles {
        for k in 0..3 {
            let uv = if uvs { &t.uvs[k].to_array()[..] } else { &[] };
            for v in t.positions[k]
                .to_array()
                .iter()
                .chain(&t.normals[k].to_array())
                .chain(uv)
            {
                bytes.extend_from_slice(&v.to_le_bytes());
            }
        }
    }
    for k in 0..triangles.len() as u32 {
        bytes.push(3);
        for corner in 0..3 {
            bytes.extend_from_slice(&(3 * k + corner).to_le_bytes());
        }
    }
    let mut file = std::fs::File::create(path)?;
    file.write_all(&bytes)?;
    file.flush()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn layout_is_header_then_vertices_then_faces() {
        let dir = std::env::temp_dir().join(format!("irad-ply-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("t.ply");
        let t = PlyTriangle {
            positions: [Vec3::ZERO, Vec3::X, Vec3::Y],
            normals: [Vec3::Z; 3],
            uvs: [Vec2::ZERO, Vec2::X, Vec2::new(0.25, 0.5)],
        };
        write(&path, "two\ntriangles", &[t, t], false).unwrap();
        let bytes = std::fs::read(&path).unwrap();
        let head = header("two triangles", 2, false);
        assert!(bytes.starts_with(head.as_bytes()));
        assert!(head.contains("element vertex 6\n") && head.contains("element face 2\n"));
        let body = &bytes[head.len()..];
        assert_eq!(body.len(), 6 * 24 + 2 * 13);
        let f = |at: usize| f32::from_le_bytes(body[at..at + 4].try_into().unwrap());
        // Vertex 1 is (1, 0, 0) with normal (0, 0, 1).
        assert_eq!(
            [f(24), f(28), f(32), f(36), f(40), f(44)],
            [1., 0., 0., 0., 0., 1.]
        );
        let faces = &body[6 * 24..];
        assert_eq!(faces[13], 3);
        let index = |at: usize| u32::from_le_bytes(faces[at..at + 4].try_into().unwrap());
        assert_eq!([index(14), index(18), index(22)], [3, 4, 5]);
        // With texture coordinates: 32-byte vertices ending in u v.
        write(&path, "uv", &[t], true).unwrap();
        let bytes = std::fs::read(&path).unwrap();
        let head = header("uv", 1, true);
        assert!(
            head.contains("property float nz\nproperty float u\nproperty float v\nelement face")
        );
        let body = &bytes[head.len()..];
        assert_eq!(body.len(), 3 * 32 + 13);
        let f = |at: usize| f32::from_le_bytes(body[at..at + 4].try_into().unwrap());
        assert_eq!([f(2 * 32 + 24), f(2 * 32 + 28)], [0.25, 0.5]);
        std::fs::remove_dir_all(&dir).ok();
    }
}
