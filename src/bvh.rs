//! The BVH: built on the CPU with obvhs, flattened into the GPU node layout that
//! glsl/include/bvh.glsl traverses.
//!
//! STUB (to be replaced): one dummy node; bvh.glsl tests every triangle.

use glam::Vec3;

use crate::gpu::{Buffer, Context, GpuResult};

/// A triangle as the traversal intersects it: `v0`, and the edges `e1 = v1 - v0`,
/// `e2 = v2 - v0` (w unused).
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
pub struct BvhTriangle {
    pub v0: [f32; 4],
    pub e1: [f32; 4],
    pub e2: [f32; 4],
}

#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
pub struct BvhNode {
    pub data: [u32; 4],
}

/// A BVH over a triangle list. The GPU sees the triangles in `triangle_order`:
/// GPU triangle i is input triangle `triangle_order[i]`, and hit records name GPU indices.
pub struct Bvh {
    pub nodes: Vec<BvhNode>,
    pub triangles: Vec<BvhTriangle>,
    pub triangle_order: Vec<u32>,
}

impl Bvh {
    pub fn build(triangles: &[[Vec3; 3]]) -> Bvh {
        let tri = |t: &[Vec3; 3]| BvhTriangle {
            v0: t[0].extend(0.0).to_array(),
            e1: (t[1] - t[0]).extend(0.0).to_array(),
            e2: (t[2] - t[0]).extend(0.0).to_array(),
        };
        Bvh {
            nodes: vec![BvhNode { data: [0; 4] }],
            triangles: triangles.iter().map(tri).collect(),
            triangle_order: (0..triangles.len() as u32).collect(),
        }
    }
}

/// The BVH on the GPU: bind both buffers under their GLSL block names (`BvhNodes`,
/// `BvhTriangles`) in every kernel that includes bvh.glsl.
pub struct GpuBvh {
    pub nodes: Buffer<BvhNode>,
    pub triangles: Buffer<BvhTriangle>,
}

impl GpuBvh {
    pub fn upload(ctx: &Context, bvh: &Bvh) -> GpuResult<GpuBvh> {
        Ok(GpuBvh {
            nodes: Buffer::from_slice(ctx, "BvhNodes", &bvh.nodes)?,
            triangles: Buffer::from_slice(ctx, "BvhTriangles", &bvh.triangles)?,
        })
    }

    pub fn bindings(&self) -> [crate::gpu::Binding<'_>; 2] {
        [
            crate::gpu::bind("BvhNodes", &self.nodes),
            crate::gpu::bind("BvhTriangles", &self.triangles),
        ]
    }
}
