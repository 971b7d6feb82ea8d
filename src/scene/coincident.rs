//! Emissive triangles with exactly the corners of another triangle: a two-sided emitter written
//! as two faces, a wall face under a light with the same corners, a duplicated face (a light
//! quad lying inside a larger wall triangle is not detected). irad's emitters are one-sided
//! (docs/DESIGN.md "Conventions") and every light table counts each emissive triangle, while a
//! ray meets only one face of such a pair, whichever the BVH visits first: the light comes out
//! neither one-sided nor two-sided and depends on the sampler. Measured on a 1 m square
//! two-sided light (two faces) 1 m over a diffuse floor, 32 x 24, max_depth 1: the power
//! table, the light BVH and restir all gave 0.088, where the same two faces 1 mm apart, back to
//! back, gave 0.349. Moving geometry behind the user's back would change the scene, so the
//! loader warns, naming the file and the count, and leaves the triangles as they are.

use std::collections::HashMap;

use super::load::is_degenerate;
use super::{Material, Triangle};

/// A triangle's corners as bits in sorted order: the same for either winding and any rotation
/// (-0 read as 0, so "-0" in one face and "0" in the other still match).
fn corner_set(t: &Triangle) -> [[u32; 3]; 3] {
    let mut p = t
        .positions
        .map(|v| v.to_array().map(|x| (x + 0.0).to_bits()));
    p.sort_unstable();
    p
}

/// One warning per mesh file with emissive triangles whose corners are exactly another
/// triangle's of the scene (either winding). `meshes`: (file for messages, its triangles).
pub fn warn_coincident_emitters(
    meshes: &[(String, Vec<Triangle>)],
    materials: &[Material],
    warnings: &mut Vec<String>,
) {
    let emits =
        |t: &Triangle| materials[t.material as usize].is_emissive() && !is_degenerate(t.positions);
    // Keyed by the emitters alone (a scene's emitters are usually a small part of it), then
    // every triangle counted against them.
    let mut faces: HashMap<[[u32; 3]; 3], u32> = meshes
        .iter()
        .flat_map(|(_, ts)| ts)
        .filter(|t| emits(t))
        .map(|t| (corner_set(t), 0))
        .collect();
    if faces.is_empty() {
        return;
    }
    for t in meshes.iter().flat_map(|(_, ts)| ts) {
        if let Some(n) = faces.get_mut(&corner_set(t)) {
            *n += 1;
        }
    }
    for (file, triangles) in meshes {
        let count = triangles
            .iter()
            .filter(|t| emits(t) && faces[&corner_set(t)] > 1)
            .count();
        if count > 0 {
            warnings.push(format!(
                "{file}: {count} emissive triangle(s) have the same corners as another triangle \
                 (a two-sided emitter written as two faces, a wall face with the same corners, \
                 a duplicate): \
                 emitters are one-sided and a ray meets only one face of such a pair, so their \
                 light comes out wrong (a quarter of a two-sided light's in a test) and differs \
                 between samplers; move the faces apart along their normal (1 mm at 1 m was \
                 enough) or keep one"
            ));
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    fn tri(p: [[f32; 3]; 3], material: u32) -> Triangle {
        Triangle {
            positions: p.map(Vec3::from),
            normals: [Vec3::Y; 3],
            material,
            uvs: [glam::Vec2::ZERO; 3],
        }
    }

    fn material(ke: f32) -> Material {
        Material {
            name: "m".into(),
            kd: Vec3::ZERO,
            ks: Vec3::ZERO,
            ns: 0.0,
            ke: Vec3::splat(ke),
            albedo_texture: None,
        }
    }

    fn warnings(meshes: &[(&str, Vec<Triangle>)]) -> Vec<String> {
        let meshes: Vec<(String, Vec<Triangle>)> = meshes
            .iter()
            .map(|(f, t)| (f.to_string(), t.clone()))
            .collect();
        let mut w = vec![];
        warn_coincident_emitters(&meshes, &[material(0.0), material(5.0)], &mut w);
        w
    }

    #[test]
    fn emitters_sharing_their_corners_with_another_face_are_counted_per_file() {
        let (a, b, c) = ([0.0, 1.0, 0.0], [1.0, 1.0, 0.0], [1.0, 1.0, 1.0]);
        // Two-sided as two faces, the reverse in another file and rotated.
        let w = warnings(&[
            ("a.obj", vec![tri([a, b, c], 1)]),
            ("b.obj", vec![tri([c, b, a], 1)]),
        ]);
        assert_eq!(w.len(), 2, "{w:?}");
        assert!(w[0].starts_with("a.obj: 1 emissive"), "{}", w[0]);
        assert!(w[1].starts_with("b.obj: 1 emissive"), "{}", w[1]);
        // A light on a wall (same winding) and a duplicate: the emitters counted.
        let w = warnings(&[("c.obj", vec![tri([a, b, c], 1), tri([b, c, a], 0)])]);
        assert!(
            w.len() == 1 && w[0].starts_with("c.obj: 1 emissive"),
            "{w:?}"
        );
        let w = warnings(&[("d.obj", vec![tri([a, b, c], 1), tri([b, c, a], 1)])]);
        assert!(
            w.len() == 1 && w[0].starts_with("d.obj: 2 emissive"),
            "{w:?}"
        );
        // 1 mm apart, or no emitter among them: none.
        let up = |p: [f32; 3]| [p[0], p[1] + 0.001, p[2]];
        assert!(warnings(&[(
            "e.obj",
            vec![tri([a, b, c], 1), tri([up(c), up(b), up(a)], 1)]
        )])
        .is_empty());
        assert!(warnings(&[("f.obj", vec![tri([a, b, c], 0), tri([c, b, a], 0)])]).is_empty());
    }
}
