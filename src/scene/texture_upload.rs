//! The albedo textures as glsl/include/texture.glsl reads them: each triangle's texture
//! coordinates as affine functions of the point (in BVH order), each material's texture
//! header, and every texture's texels as half floats back to back.

use bytemuck::{Pod, Zeroable};
use glam::{DVec3, Vec4};
use half::f16;

use super::{Scene, Wrap};

/// texture.glsl's NO_TEXTURE: a material without a texture.
pub const NO_TEXTURE: u32 = u32::MAX;

/// texture.glsl's TriangleUv: u = origin.w + du.xyz . (p - origin.xyz),
/// v = du.w + dv.xyz . (p - origin.xyz).
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct TriangleUv {
    pub origin: Vec4,
    pub du: Vec4,
    pub dv: Vec4,
}

/// The GLSL layout TriangleUv mirrors (src/gpu/contracts.rs checks it).
#[cfg(test)]
pub(crate) const GPU_LAYOUTS: &[crate::gpu::contracts::GpuLayout] = {
    use crate::gpu::contracts::gpu_layout;
    &[gpu_layout!(TriangleUv as "TriangleUv" { origin, du, dv })]
};

/// Whether any material has a texture: the kernels' SCENE_HAS_TEXTURES.
pub fn has_textures(scene: &Scene) -> bool {
    scene.materials.iter().any(|m| m.albedo_texture.is_some())
}

/// Each triangle's TriangleUv, in `order` (the BVH's triangle order): the gradients of u and v
/// in the triangle's plane, from the dual basis of its edges, in f64.
pub fn triangle_uvs(scene: &Scene, order: &[u32]) -> Vec<TriangleUv> {
    order
        .iter()
        .map(|&k| {
            let t = &scene.triangles[k as usize];
            let [p0, p1, p2] = t.positions.map(|p| p.as_dvec3());
            let (e1, e2) = (p1 - p0, p2 - p0);
            let n = e1.cross(e2);
            let n2 = n.length_squared();
            // b1 . e1 = 1, b1 . e2 = 0; b2 . e1 = 0, b2 . e2 = 1 (zero for a degenerate
            // triangle, which the loader drops).
            let (b1, b2) = if n2 > 0.0 {
                (e2.cross(n) / n2, n.cross(e1) / n2)
            } else {
                (DVec3::ZERO, DVec3::ZERO)
            };
            let [uv0, uv1, uv2] = t.uvs.map(|uv| uv.as_dvec2());
            let gradient = |d1: f64, d2: f64| (b1 * d1 + b2 * d2).as_vec3();
            let du = gradient(uv1.x - uv0.x, uv2.x - uv0.x);
            let dv = gradient(uv1.y - uv0.y, uv2.y - uv0.y);
            TriangleUv {
                origin: t.positions[0].extend(t.uvs[0].x),
                du: du.extend(t.uvs[0].y),
                dv: dv.extend(0.0),
            }
        })
        .collect()
}

fn wrap_code(w: Wrap) -> u32 {
    match w {
        Wrap::Repeat => 0,
        Wrap::Mirror => 1,
        Wrap::Clamp => 2,
    }
}

/// Each material's texture header (texture.glsl's MaterialTextures) and the texels of every
/// texture, back to back, as (r | g << 16, b) half floats.
pub fn texture_tables(scene: &Scene) -> (Vec<[u32; 4]>, Vec<[u32; 2]>) {
    let mut first = Vec::with_capacity(scene.textures.len());
    let mut texels = Vec::new();
    for t in &scene.textures {
        first.push(texels.len() as u32);
        let half = |v: f32| u32::from(f16::from_f32(v).to_bits());
        texels.extend(
            t.texels
                .iter()
                .map(|c| [half(c.x) | half(c.y) << 16, half(c.z)]),
        );
    }
    let headers = scene
        .materials
        .iter()
        .map(|m| match m.albedo_texture {
            Some(k) => {
                let t = &scene.textures[k as usize];
                [
                    first[k as usize],
                    t.width,
                    t.height,
                    wrap_code(t.wrap[0]) | wrap_code(t.wrap[1]) << 2,
                ]
            }
            None => [NO_TEXTURE, 0, 0, 0],
        })
        .collect();
    (headers, texels)
}

/// Device bytes of a scene's texels: what device_fit checks against maxStorageBufferRange.
pub fn texel_bytes(scene: &Scene) -> u64 {
    scene
        .textures
        .iter()
        .map(|t| 8 * t.width as u64 * t.height as u64)
        .sum()
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec2;

    #[test]
    fn the_affine_uv_gives_each_corner_its_uv() {
        let mut scene = crate::scene::default_scene();
        scene.triangles[0].uvs = [
            Vec2::new(0.1, 0.2),
            Vec2::new(3.0, -1.0),
            Vec2::new(0.5, 7.0),
        ];
        let uv = triangle_uvs(&scene, &[0])[0];
        let t = &scene.triangles[0];
        for (p, expected) in t.positions.iter().zip(t.uvs) {
            let d = *p - uv.origin.truncate();
            let got = Vec2::new(
                uv.origin.w + uv.du.truncate().dot(d),
                uv.du.w + uv.dv.truncate().dot(d),
            );
            assert!((got - expected).length() < 1e-5, "{got} vs {expected}");
        }
        // A point off the plane maps as its projection: the gradients lie in the plane.
        let n = (t.positions[1] - t.positions[0]).cross(t.positions[2] - t.positions[0]);
        assert!(uv.du.truncate().dot(n).abs() < 1e-4 * n.length());
    }
}
