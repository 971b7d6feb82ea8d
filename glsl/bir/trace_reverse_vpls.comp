#version 450
// Reverse VPLs (Segovia 06 Section 3.1): the ends x2 of length-2 camera paths. A pool of M
// camera points x1 (G-buffer texels at pseudo-random pixels, the same pool for the batch) is
// drawn; reverse VPL k starts from pool point k mod M, leaves it in a cosine-distributed
// direction about its shading normal on the camera's side, and ends at the first hit x2.
//
// Density (Eq. 7): p(x2) = mean over x1 of p(x1 -> x2), p(x1 -> x2) = cos(theta_1) / pi *
// |cos(theta_2)| / d^2 * V(x1, x2). irad evaluates Eq. 7 over the pool the VPLs were drawn from
// (M shadow rays per VPL). Given the pool, the k mod M schedule is Veach's multi-sample model
// with n_m = R / M samples per pool point, and dividing by R times this mean is its balance
// heuristic: the density is exact, not an estimate, so 1 / p(x2) carries no Jensen bias (the
// paper estimates Eq. 7 with fresh camera samples, which is biased for small M; a departure).
// What remains is support: a surface no pool point sees gets no reverse VPL this batch;
// find_uncovered_vpls.comp gives the standard VPLs there the full weight under `both`.
//
// Numbers: PCG keyed by (seed, k, dimension); dimensions 0-1 the direction. The pool:
// reverse_pool.glsl.
//
// Eq. 7's M shadow rays are split over dispatches, pool points [pool_begin, pool_end) each
// (lavapipe's loop budget, docs/DESIGN.md "The loop budget"): every dispatch traces x2 again (the same ray),
// the first writes the VPL and its share of the density, the others add theirs, and the last
// empties the VPL where the density is 0.

#extension GL_GOOGLE_include_directive : require

layout(local_size_x = 64, local_size_y = 1, local_size_z = 1) in;

#define REVERSE_VPL_WRITE
#define VPL_NO_BUFFER
#include "bvh.glsl"
#include "scene.glsl"
#include "sampling.glsl"
#include "gbuffer.glsl"
#include "vpl.glsl"
#include "reverse_vpl.glsl"
#include "reverse_pool.glsl"

layout(push_constant) uniform ReverseParams {
    uint count;   // R reverse VPLs
    uint pool;    // M camera points
    uint seed;
    uint pixels;  // G-buffer texels
    uint pool_begin;  // this dispatch's pool points
    uint pool_end;
} params;

void main() {
    uint k = gl_GlobalInvocationID.x;
    if (k >= params.count) return;
    bool first = params.pool_begin == 0u;
    bool last = params.pool_end >= params.pool;
    // A later dispatch adds to a VPL an earlier one wrote, unless that one found no x2.
    if (!first && vpl_kind(reverse_vpls[k]) == VPL_NONE) return;
    Vpl v;
    v.position = vec4(0.0, 0.0, 0.0, uintBitsToFloat(VPL_NONE));
    v.normal = vec4(0.0);
    v.power = vec4(0.0);
    v.incident = vec4(0.0);

    vec3 x1, n1, side1;
    if (!pool_point(params.seed, params.pixels, k % params.pool, x1, n1, side1)) {
        reverse_vpls[k] = v;
        return;
    }
    vec2 u = vec2(random(params.seed, k, 0x72657672u, 0u), random(params.seed, k, 0x72657672u, 1u));
    vec3 w = to_world(sample_cosine_hemisphere(u), n1);
    RayHit hit;
    if (dot(w, side1) <= 0.0 || !trace_closest(offset_origin(x1, side1), w, infinity(), hit)) {
        reverse_vpls[k] = v;
        return;
    }
    vec3 x2 = offset_origin(x1, side1) + hit.t * w;
    vec3 ng2 = shading_triangles[hit.triangle].geometric_normal.xyz;
    vec3 side2 = dot(-w, ng2) >= 0.0 ? ng2 : -ng2;
    vec3 ns2 = shading_normal(hit.triangle, hit.barycentrics);
    vec3 n2 = dot(ns2, side2) >= 0.0 ? ns2 : -ns2;
    vec3 origin2 = offset_origin(x2, side2);

    // Eq. 7 over this dispatch's pool points.
    float density = pool_density(params.seed, params.pixels, params.pool, params.pool_begin,
                                 params.pool_end, x2, ng2, side2, origin2, false);
    if (!first) density += reverse_vpls[k].power.w;
    if (last && !(density > 0.0)) {
        reverse_vpls[k] = v;
        return;
    }
    v.position = vec4(origin2, uintBitsToFloat(VPL_AREA));
    v.normal = vec4(n2, uintBitsToFloat(triangle_material(hit.triangle)));
    v.power = vec4(0.0, 0.0, 0.0, density);
    v.incident = vec4(side2, uintBitsToFloat(hit.triangle));
    reverse_vpls[k] = v;
}
