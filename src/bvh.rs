//! The BVH: built on the CPU with obvhs, flattened into the GPU node layout that
//! glsl/include/bvh.glsl traverses.
//!
//! Builder: obvhs's `build_cwbvh_from_tris` with `BvhBuildParams::medium_build()` minus its
//! (already off) spatial pre-splits: a PLOC BVH2 (Meister and Bittner 2018) improved by
//! parallel reinsertion, then collapsed into a compressed wide BVH8 (Ylitie, Karras and
//! Laine 2017, "Efficient Incoherent Ray Traversal on GPUs Through Compressed Wide BVHs").
//! Why this one:
//! - CWBVH is the layout whose traversal won on lavapipe, by 1.7x over a BVH2 with both
//!   children's boxes in the parent (glsl/include/bvh.glsl lists what was measured). On
//!   lavapipe every storage-buffer load is a scalar loop over the active lanes, so traversal
//!   time is mostly loads per ray: an 80-byte CWBVH node (5 loads) tests 8 children, a 64-byte
//!   BVH2 node (4 loads) tests 2. It is also obvhs's fastest CPU structure, the one `irad bench
//!   rays` compares against, and the one tray_racing traverses in compute shaders.
//! - The presets from `very_fast_build` to `very_slow_build` traced within noise of each other
//!   on the benchmark's 200k-triangle sphere (GPU and CPU); `medium_build` builds it in ~0.2 s.
//! - No spatial pre-splits, so every input triangle sits in exactly one leaf and
//!   `triangle_order` is a permutation (other code indexes per-triangle data through it).
//!
//! The GPU layout is obvhs's `CwBvhNode` byte for byte (80 bytes, 5 x uvec4), and the
//! triangles are stored in the CWBVH's primitive order (leaves reference consecutive runs),
//! so no index buffer is needed on the GPU.

use std::time::Duration;

use glam::{Vec3, Vec3A};
use obvhs::cwbvh::{builder::build_cwbvh_from_tris, node::CwBvhNode, CwBvh};
use obvhs::triangle::Triangle;
use obvhs::BvhBuildParams;

use crate::gpu::{bind, Binding, Buffer, Context, GpuError, GpuResult};

pub mod procedural;

/// Entries of the per-invocation traversal stack in bvh.glsl (BVH_STACK_SIZE). A CWBVH
/// traversal holds at most one entry per tree level below the root, so trees up to this depth
/// are traversed exactly (`Bvh::depth`; a 200k-triangle mesh gives 10). A deeper tree, which
/// only a degenerate input could produce, would lose pushes (rays missing silently), so
/// `GpuBvh::upload` refuses it.
pub const GPU_STACK_SIZE: usize = 32;

/// A triangle as the traversal intersects it: `v0` and the edges `e1 = v1 - v0`,
/// `e2 = v2 - v0` (w unused, zero).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct BvhTriangle {
    pub v0: [f32; 4],
    pub e1: [f32; 4],
    pub e2: [f32; 4],
}

impl BvhTriangle {
    pub fn new(t: &[Vec3; 3]) -> Self {
        BvhTriangle {
            v0: t[0].extend(0.0).to_array(),
            e1: (t[1] - t[0]).extend(0.0).to_array(),
            e2: (t[2] - t[0]).extend(0.0).to_array(),
        }
    }

    /// Moller-Trumbore exactly as bvh.glsl computes it: the hit (t, u, v) with
    /// `0 < t < t_max` from either side, u and v the weights of v1 and v2.
    pub fn intersect(&self, origin: Vec3, direction: Vec3, t_max: f32) -> Option<(f32, f32, f32)> {
        let v0 = Vec3::from_slice(&self.v0);
        let e1 = Vec3::from_slice(&self.e1);
        let e2 = Vec3::from_slice(&self.e2);
        let p = direction.cross(e2);
        let det = e1.dot(p);
        let inv_det = 1.0 / det;
        let s = origin - v0;
        let u = s.dot(p) * inv_det;
        let q = s.cross(e1);
        let v = direction.dot(q) * inv_det;
        let t = e2.dot(q) * inv_det;
        (det != 0.0 && u >= 0.0 && v >= 0.0 && u + v <= 1.0 && t > 0.0 && t < t_max)
            .then_some((t, u, v))
    }
}

/// One CWBVH node: obvhs's `CwBvhNode` as 20 words (bvh.glsl names the 5 uvec4s).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct BvhNode {
    pub data: [u32; 20],
}

/// The GLSL layouts of the structs above (src/gpu/contracts.rs checks them). `BvhNode`'s one
/// Rust field holds bvh.glsl's five uvec4 members, written out by hand.
#[cfg(test)]
pub(crate) const GPU_LAYOUTS: &[crate::gpu::contracts::GpuLayout] = {
    use crate::gpu::contracts::{gpu_layout, Glsl, GpuField, GpuLayout};
    use core::mem::{offset_of, size_of};
    const fn node_member(rust: &'static str, member: &'static str, word: usize) -> GpuField {
        GpuField {
            rust,
            member: Some(member),
            offset: offset_of!(BvhNode, data) + 4 * word,
            within: 0,
        }
    }
    const _: fn(BvhNode) = |v: BvhNode| {
        let BvhNode { data: _ } = v;
    };
    &[
        gpu_layout!(BvhTriangle as "BvhTriangle" { v0, e1, e2 }),
        GpuLayout {
            rust: concat!(module_path!(), "::BvhNode"),
            glsl: Glsl::Struct("BvhNode"),
            size: size_of::<BvhNode>(),
            fields: &[
                node_member("data[0..4]", "origin_exponents", 0),
                node_member("data[4..8]", "bases_meta", 4),
                node_member("data[8..12]", "quantized_x", 8),
                node_member("data[12..16]", "quantized_y", 12),
                node_member("data[16..20]", "quantized_z", 16),
            ],
        },
    ]
};

impl From<&CwBvhNode> for BvhNode {
    fn from(node: &CwBvhNode) -> Self {
        bytemuck::cast(*node)
    }
}

/// A BVH over a triangle list. The GPU sees the triangles in `triangle_order`:
/// GPU triangle i is input triangle `triangle_order[i]` (a permutation), and hit records
/// name GPU indices.
pub struct Bvh {
    pub nodes: Vec<BvhNode>,
    pub triangles: Vec<BvhTriangle>,
    pub triangle_order: Vec<u32>,
}

impl Bvh {
    /// Builds the BVH of `triangles` (finite vertices; degenerate triangles are kept and never
    /// hit). An empty list gives a root with no children, which every ray misses.
    pub fn build(triangles: &[[Vec3; 3]]) -> Bvh {
        Self::from_cwbvh(&build_cwbvh(triangles), triangles)
    }

    /// The GPU layout of `cwbvh`, built over `triangles` by `build_cwbvh`.
    pub fn from_cwbvh(cwbvh: &CwBvh, triangles: &[[Vec3; 3]]) -> Bvh {
        if cwbvh.nodes.is_empty() {
            return Bvh {
                nodes: vec![BvhNode { data: [0; 20] }],
                triangles: Vec::new(),
                triangle_order: Vec::new(),
            };
        }
        debug_assert_eq!(cwbvh.primitive_indices.len(), triangles.len());
        Bvh {
            nodes: cwbvh.nodes.iter().map(BvhNode::from).collect(),
            triangles: cwbvh
                .primitive_indices
                .iter()
                .map(|&i| BvhTriangle::new(&triangles[i as usize]))
                .collect(),
            triangle_order: cwbvh.primitive_indices.clone(),
        }
    }

    /// Levels of the tree (1 for a root whose children are all leaves).
    pub fn depth(&self) -> usize {
        let nodes: &[CwBvhNode] = bytemuck::cast_slice(&self.nodes);
        max_depth(nodes, 0)
    }
}

/// obvhs's triangle type, from irad's.
pub fn obvhs_triangles(triangles: &[[Vec3; 3]]) -> Vec<Triangle> {
    triangles
        .iter()
        .map(|t| Triangle {
            v0: Vec3A::from(t[0]),
            v1: Vec3A::from(t[1]),
            v2: Vec3A::from(t[2]),
        })
        .collect()
}

/// The CWBVH that `Bvh::build` flattens (the benchmark traverses it on the CPU too).
pub fn build_cwbvh(triangles: &[[Vec3; 3]]) -> CwBvh {
    if triangles.is_empty() {
        return CwBvh::default();
    }
    let params = BvhBuildParams {
        pre_split: false,
        ..BvhBuildParams::medium_build()
    };
    build_cwbvh_from_tris(
        &obvhs_triangles(triangles),
        params,
        &mut Duration::default(),
    )
}

fn max_depth(nodes: &[CwBvhNode], index: usize) -> usize {
    let node = &nodes[index];
    1 + (0..8)
        .filter(|&ch| !node.is_child_empty(ch) && !node.is_leaf(ch))
        .map(|ch| max_depth(nodes, node.child_node_index(ch) as usize))
        .max()
        .unwrap_or(0)
}

/// The BVH on the GPU: bind its buffers under their GLSL block names (`BvhNodes`,
/// `BvhTriangles`, `LoopCuts`) in every kernel that includes bvh.glsl.
pub struct GpuBvh {
    pub nodes: Buffer<BvhNode>,
    pub triangles: Buffer<BvhTriangle>,
    /// bvh.glsl's `loop_cuts`: 1 once a traversal was cut short by the device's loop limit
    /// (lavapipe: 65535 loop iterations an invocation), zeroed at upload and by
    /// `clear_loop_cuts` and `check_loop_cuts`.
    pub loop_cuts: Buffer<u32>,
}

impl GpuBvh {
    pub fn upload(ctx: &Context, bvh: &Bvh) -> GpuResult<GpuBvh> {
        let depth = bvh.depth();
        if depth > GPU_STACK_SIZE {
            return Err(GpuError::BvhTooDeep {
                depth,
                limit: GPU_STACK_SIZE,
            });
        }
        Ok(GpuBvh {
            nodes: Buffer::from_slice(ctx, "BvhNodes", &bvh.nodes)?,
            triangles: Buffer::from_slice(ctx, "BvhTriangles", &bvh.triangles)?,
            loop_cuts: Buffer::zeroed(ctx, "LoopCuts", 1)?,
        })
    }

    pub fn bindings(&self) -> [Binding<'_>; 3] {
        [
            bind("BvhNodes", &self.nodes),
            bind("BvhTriangles", &self.triangles),
            bind("LoopCuts", &self.loop_cuts),
        ]
    }

    /// Forgets any cut traversal recorded so far (before a render). The GPU must be idle on
    /// the buffer (every submission is waited for).
    pub fn clear_loop_cuts(&self) -> GpuResult<()> {
        self.loop_cuts.write(&[0])
    }

    /// After the submissions that traced through this BVH have completed: the error
    /// [`GpuError::TraversalCut`] when one of their traversals was cut short by the device's
    /// loop limit (its hits, and what was computed from them, are wrong), clearing the record.
    pub fn check_loop_cuts(&self) -> GpuResult<()> {
        if self.loop_cuts.read()?[0] == 0 {
            return Ok(());
        }
        self.clear_loop_cuts()?;
        Err(GpuError::TraversalCut)
    }
}
