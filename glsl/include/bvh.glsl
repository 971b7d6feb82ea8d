// BVH traversal (src/bvh.rs builds the layout). Declares bindings 0, 1 and 63 (LoopCuts);
// kernels that include this number their own bindings from 2 (scene.glsl holds 2..9).
//
// The BVH is obvhs's compressed wide BVH8 (Ylitie, Karras and Laine 2017), traversed as in
// their paper: a node holds its 8 children's boxes quantized to 8 bits in the node's own
// grid, a ray tests all 8 with one node fetch, and the hit children come back as bits ordered
// by the ray's octant, so the nearest-first order costs one findMSB. The loop is the one of
// tray_racing (DGriffin91): visit one node, then test that node's hit triangles in an inner
// loop, then pop.
//
// Why, on lavapipe (Mesa 22.3, 8-wide): a storage-buffer load compiles to a scalar loop over
// the active lanes, per load instruction, and both sides of every branch run under masks. So
// time goes to load instructions per ray (node loads ~45%, triangle tests ~25% of it), and
// to code run by lanes with nothing to do. Measured against this loop on random rays:
//   BVH2, both children's boxes in the parent, nearest first: 0.57x
//   one loop doing a node or a triangle per iteration: 0.55x
//   one node and one triangle per iteration (triangle groups stacked): 0.9x
//   triangle postponing until 2-5 of 8 lanes have triangles (Ylitie et al.): 0.7-0.95x
//   nodes fetched as 10 uvec2 instead of 5 uvec4: 0.8x; as 64-bit words: 0.8-1.0x
//   lanes sharing the first lane's node through subgroupBroadcastFirst: 0.75x
//   top 818 nodes in a uniform buffer (gathered, not looped): 0.85x
//   root visit peeled out of the loop, stack of 8 to 64 entries, stack in shared memory: 1.0x
//   compare-and-select slab min/max instead of GLSL min/max: kept (3% fewer instructions)
//   subgroup-cooperative, one ray per subgroup, child j per lane (as obvhs's CPU SIMD):
//     0.3-0.45x (loads at subgroup-uniform addresses still loop over the lanes on lavapipe,
//     and a shared step costs over half a full 8-ray step; not kept)
#ifndef BVH_GLSL
#define BVH_GLSL

// obvhs's CwBvhNode, 80 bytes.
struct BvhNode {
    uvec4 origin_exponents; // xyz: grid origin p (float bits); w: exponent bytes ex, ey, ez, imask
    uvec4 bases_meta;       // x: first child node; y: first triangle; zw: 8 child meta bytes
    uvec4 quantized_x;      // xy: 8 child min bytes; zw: 8 child max bytes
    uvec4 quantized_y;
    uvec4 quantized_z;
};
// v0 and the edges e1 = v1 - v0, e2 = v2 - v0 (w unused), in BVH leaf order.
struct BvhTriangle { vec4 v0; vec4 e1; vec4 e2; };

layout(set = 0, binding = 0, std430) readonly buffer BvhNodes { BvhNode bvh_nodes[]; };
layout(set = 0, binding = 1, std430) readonly buffer BvhTriangles { BvhTriangle bvh_triangles[]; };
// Set to 1 by a traversal that the device's loop limit cut short, or by a search that found
// its trip count past the bound its dispatches were planned by (weigh_env_cube.comp) (lavapipe:
// 65535 loop iterations a group of lanes, all loops together, then every loop breaks out
// silently; docs/DESIGN.md "The loop budget"). The host zeroes it before a render and refuses the render when it reads 1
// (src/bvh.rs GpuBvh::check_loop_cuts). Binding 63: far above the numbers kernels give their
// own bindings (2..36 now), so a kernel's next binding does not run into it (reflection
// refuses two bindings of one number: src/gpu/reflect.rs).
layout(set = 0, binding = 63, std430) writeonly buffer LoopCuts { uint loop_cuts; };

struct RayHit {
    float t;           // distance along the (unit or not) direction: origin + t * direction
    uint triangle;     // GPU triangle index (BVH order)
    vec2 barycentrics; // (u, v): the hit is (1 - u - v) v0 + u v1 + v v2
};

#define BVH_NO_TRIANGLE 0xffffffffu
// One entry per tree level at most (src/bvh.rs GPU_STACK_SIZE).
#define BVH_STACK_SIZE 32

// Moller-Trumbore; accepts hits with 0 < t < t_max from either side. src/bvh.rs mirrors it
// (BvhTriangle::intersect).
bool bvh_intersect_triangle(vec3 origin, vec3 direction, uint index, float t_max,
                            out float t, out vec2 uv) {
    vec3 v0 = bvh_triangles[index].v0.xyz;
    vec3 e1 = bvh_triangles[index].e1.xyz;
    vec3 e2 = bvh_triangles[index].e2.xyz;
    vec3 p = cross(direction, e2);
    float det = dot(e1, p);
    float inv_det = 1.0 / det;
    vec3 s = origin - v0;
    float u = dot(s, p) * inv_det;
    vec3 q = cross(s, e1);
    float v = dot(direction, q) * inv_det;
    t = dot(e2, q) * inv_det;
    uv = vec2(u, v);
    return det != 0.0 && u >= 0.0 && v >= 0.0 && u + v <= 1.0 && t > 0.0 && t < t_max;
}

// Plain compare-and-select: one instruction on x86, where GLSL min/max become NaN-aware
// sequences on lavapipe (operands here are never NaN).
float bvh_max(float a, float b) { return a > b ? a : b; }
float bvh_min(float a, float b) { return a < b ? a : b; }

uint bvh_byte(uint word, uint i) {
    return bitfieldExtract(word, int(8u * i), 8);
}

// Bit 24 + (slot ^ octant) for each hit internal child, and the unary triangle count shifted
// by the leaf's first triangle offset for each hit leaf (obvhs CwBvhNode::intersect_ray).
uint bvh_intersect_node(BvhNode node, vec3 origin, vec3 inv_dir, uint oct_inv4, float t_max) {
    vec3 p = uintBitsToFloat(node.origin_exponents.xyz);
    uint e = node.origin_exponents.w;
    vec3 extent = uintBitsToFloat(uvec3(bvh_byte(e, 0u), bvh_byte(e, 1u), bvh_byte(e, 2u)) << 23);
    // Child plane q (0..255) of axis a is at p + q * extent, hit at t = q * scale + offset.
    vec3 scale = extent * inv_dir;
    vec3 offset = (p - origin) * inv_dir;
    bvec3 negative = lessThan(inv_dir, vec3(0.0));
    uint hit_mask = 0u;
    for (uint half_index = 0u; half_index < 2u; ++half_index) {
        uint meta4 = half_index == 0u ? node.bases_meta.z : node.bases_meta.w;
        uint is_inner4 = (meta4 & (meta4 << 1)) & 0x10101010u;
        uint inner_mask4 = (is_inner4 >> 4) * 0xffu;
        uint bit_index4 = (meta4 ^ (oct_inv4 & inner_mask4)) & 0x1f1f1f1fu;
        uint child_bits4 = (meta4 >> 5) & 0x07070707u;

        uint lo_x = half_index == 0u ? node.quantized_x.x : node.quantized_x.y;
        uint hi_x = half_index == 0u ? node.quantized_x.z : node.quantized_x.w;
        uint lo_y = half_index == 0u ? node.quantized_y.x : node.quantized_y.y;
        uint hi_y = half_index == 0u ? node.quantized_y.z : node.quantized_y.w;
        uint lo_z = half_index == 0u ? node.quantized_z.x : node.quantized_z.y;
        uint hi_z = half_index == 0u ? node.quantized_z.z : node.quantized_z.w;
        // Near and far planes by the ray's direction signs.
        uvec3 near4 = uvec3(negative.x ? hi_x : lo_x, negative.y ? hi_y : lo_y,
                            negative.z ? hi_z : lo_z);
        uvec3 far4 = uvec3(negative.x ? lo_x : hi_x, negative.y ? lo_y : hi_y,
                           negative.z ? lo_z : hi_z);
        for (uint j = 0u; j < 4u; ++j) {
            vec3 near_t = vec3(uvec3(bvh_byte(near4.x, j), bvh_byte(near4.y, j),
                                     bvh_byte(near4.z, j))) * scale + offset;
            vec3 far_t = vec3(uvec3(bvh_byte(far4.x, j), bvh_byte(far4.y, j),
                                    bvh_byte(far4.z, j))) * scale + offset;
            float t_enter = bvh_max(bvh_max(near_t.x, near_t.y), bvh_max(near_t.z, 0.0));
            float t_exit = bvh_min(bvh_min(far_t.x, far_t.y), bvh_min(far_t.z, t_max));
            if (t_enter <= t_exit) {
                hit_mask |= bvh_byte(child_bits4, j) << bvh_byte(bit_index4, j);
            }
        }
    }
    return hit_mask;
}

// Closest hit (any_hit false) or the first hit found (any_hit true) with 0 < t < t_max.
bool bvh_traverse(vec3 origin, vec3 direction, float t_max, bool any_hit, out RayHit hit) {
    hit.t = t_max;
    hit.triangle = BVH_NO_TRIANGLE;
    hit.barycentrics = vec2(0.0);
    // Box tests divide by the direction: an exactly zero component becomes a tiny positive one,
    // so no 0 * inf = NaN (the slab is then hit over a huge t range, as it should be). The
    // triangle tests use the direction as given.
    vec3 box_dir = mix(direction, vec3(1.1920929e-7), equal(direction, vec3(0.0)));
    vec3 inv_dir = vec3(1.0) / box_dir;
    // Child slots were ordered by octant at build time: XOR with this visits near ones first.
    uint oct_inv4 = (box_dir.x < 0.0 ? 0u : 0x04040404u) | (box_dir.y < 0.0 ? 0u : 0x02020202u) |
                    (box_dir.z < 0.0 ? 0u : 0x01010101u);

    uvec2 stack[BVH_STACK_SIZE];
    uint stack_size = 0u;
    // (first child node, hit bits << 24 | imask) and (first triangle, hit triangle bits).
    uvec2 node_group = uvec2(0u, 0x80000000u);
    uvec2 triangle_group = uvec2(0u);

    while (true) {
        if ((node_group.y & 0xff000000u) != 0u) {
            uint bits = node_group.y;
            uint bit = uint(findMSB(bits));
            node_group.y &= ~(1u << bit);
            if ((node_group.y & 0xff000000u) != 0u && stack_size < BVH_STACK_SIZE) {
                stack[stack_size++] = node_group;
            }
            uint slot = (bit - 24u) ^ (oct_inv4 & 0xffu);
            uint child = node_group.x + bitCount(bits & ~(0xffffffffu << slot));
            BvhNode node = bvh_nodes[child];
            uint hit_mask = bvh_intersect_node(node, origin, inv_dir, oct_inv4, hit.t);
            uint imask = node.origin_exponents.w >> 24;
            node_group = uvec2(node.bases_meta.x, (hit_mask & 0xff000000u) | imask);
            triangle_group = uvec2(node.bases_meta.y, hit_mask & 0x00ffffffu);
        } else {
            triangle_group = uvec2(0u);
            node_group = uvec2(0u);
        }

        // A guarded do-while, not a while: gallivm tests a loop's lanes at the end of its
        // body, so a test at the top costs one more whole body, run with every lane masked.
        if (triangle_group.y != 0u) {
            do {
                uint bit = uint(findMSB(triangle_group.y));
                triangle_group.y &= ~(1u << bit);
                uint index = triangle_group.x + bit;
                float t;
                vec2 uv;
                if (bvh_intersect_triangle(origin, direction, index, hit.t, t, uv)) {
                    hit.t = t;
                    hit.triangle = index;
                    hit.barycentrics = uv;
                    if (any_hit) {
                        return true;
                    }
                }
            } while (triangle_group.y != 0u);
        }

        if ((node_group.y & 0xff000000u) == 0u) {
            if (stack_size == 0u) {
                break;
            }
            node_group = stack[--stack_size];
        }
    }
    // The loop ends itself only with no work left: no node bits (an iteration that goes on
    // leaves some, its own node's or a popped entry's) and no untested triangle (the triangle
    // loop ends on none). Work left means the loop limit broke out of a loop: one branch and a
    // rare store after the loop, no test inside it (the any-hit return is a natural end too).
    if ((node_group.y & 0xff000000u) != 0u || triangle_group.y != 0u) {
        loop_cuts = 1u;
    }
    return hit.triangle != BVH_NO_TRIANGLE;
}

// The closest hit with 0 < t < t_max.
bool trace_closest(vec3 origin, vec3 direction, float t_max, out RayHit hit) {
    return bvh_traverse(origin, direction, t_max, false, hit);
}

// Whether anything is hit with 0 < t < t_max (shadow rays).
bool trace_any(vec3 origin, vec3 direction, float t_max) {
    RayHit hit;
    return bvh_traverse(origin, direction, t_max, true, hit);
}

#endif
