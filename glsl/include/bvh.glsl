// BVH traversal (src/bvh.rs builds the layout). Declares bindings 0 and 1; kernels that
// include this number their own bindings from 2.
//
// STUB (to be replaced): tests every triangle.
#ifndef BVH_GLSL
#define BVH_GLSL

struct BvhNode { uvec4 data; };
struct BvhTriangle { vec4 v0; vec4 e1; vec4 e2; };

layout(set = 0, binding = 0, std430) readonly buffer BvhNodes { BvhNode bvh_nodes[]; };
layout(set = 0, binding = 1, std430) readonly buffer BvhTriangles { BvhTriangle bvh_triangles[]; };

struct RayHit {
    float t;           // distance along the (unit or not) direction: origin + t * direction
    uint triangle;     // GPU triangle index (BVH order)
    vec2 barycentrics; // (u, v): the hit is (1 - u - v) v0 + u v1 + v v2
};

// Moller-Trumbore; accepts hits with 0 < t < t_max from either side.
bool bvh_intersect_triangle(vec3 origin, vec3 direction, BvhTriangle tri, float t_max,
                            out float t, out vec2 uv) {
    vec3 p = cross(direction, tri.e2.xyz);
    float det = dot(tri.e1.xyz, p);
    if (abs(det) < 1e-30) return false;
    float inv_det = 1.0 / det;
    vec3 s = origin - tri.v0.xyz;
    float u = dot(s, p) * inv_det;
    if (u < 0.0 || u > 1.0) return false;
    vec3 q = cross(s, tri.e1.xyz);
    float v = dot(direction, q) * inv_det;
    if (v < 0.0 || u + v > 1.0) return false;
    t = dot(tri.e2.xyz, q) * inv_det;
    uv = vec2(u, v);
    return t > 0.0 && t < t_max;
}

// The closest hit with 0 < t < t_max.
bool trace_closest(vec3 origin, vec3 direction, float t_max, out RayHit hit) {
    hit.t = t_max;
    hit.triangle = 0xffffffffu;
    hit.barycentrics = vec2(0.0);
    uint n = uint(bvh_triangles.length());
    for (uint i = 0u; i < n; ++i) {
        float t;
        vec2 uv;
        if (bvh_intersect_triangle(origin, direction, bvh_triangles[i], hit.t, t, uv)) {
            hit.t = t;
            hit.triangle = i;
            hit.barycentrics = uv;
        }
    }
    return hit.triangle != 0xffffffffu;
}

// Whether anything is hit with 0 < t < t_max (shadow rays).
bool trace_any(vec3 origin, vec3 direction, float t_max) {
    uint n = uint(bvh_triangles.length());
    for (uint i = 0u; i < n; ++i) {
        float t;
        vec2 uv;
        if (bvh_intersect_triangle(origin, direction, bvh_triangles[i], t_max, t, uv)) return true;
    }
    return false;
}

#endif
