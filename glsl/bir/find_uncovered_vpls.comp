#version 450
// bir's `both` is a_s times the standard side's estimate plus a_r times the reverse side's
// (update_side_weights.comp). The reverse side only reaches surfaces that some point of the
// batch's pool of camera points sees (trace_reverse_vpls.comp): light that leaves a surface no
// pool point sees is estimated by the standard side alone, and at weight a_s the image loses
// a_r of it (Segovia 06's union has the same hole). This kernel finds the standard surface VPLs
// whose point and emitting side no pool point reaches (Eq. 7's density over the pool is zero
// there) and gives them weight 1: it sets incident.w = 1 (resample_vpls.comp then weighs the
// draw by 1 instead of a_s) and multiplies their power by `uncovered_scale` (1 / a_s where
// the VPLs are gathered at a_s without resampling; 1 otherwise). Every VPL position is then
// weighed a_s + a_r = 1 where both sides reach it and 1 where only the standard side does, so
// `both` stays unbiased whatever the pool misses. The side is taken from the VPL's shading
// normal (the geometric normal is not stored; the same on flat-shaded meshes). At most M shadow
// rays per VPL, fewer where a pool point sees it (the test stops at the first).
//
// The pool is split over dispatches, points [pool_begin, pool_end) each (lavapipe's loop
// budget, docs/DESIGN.md "The loop budget"). incident.w carries "no pool point so far reaches it" between
// them: the first dispatch sets it where its points miss, a later one clears it where its
// points reach, and the last scales the power of those still marked.

#extension GL_GOOGLE_include_directive : require

layout(local_size_x = 64, local_size_y = 1, local_size_z = 1) in;

#define VPL_READ_WRITE
#include "bvh.glsl"
#include "scene.glsl"
#include "sampling.glsl"
#include "gbuffer.glsl"
#include "vpl.glsl"
#include "reverse_pool.glsl"

layout(push_constant) uniform CoverParams {
    uint vpl_begin;        // standard VPL slots [vpl_begin, vpl_end)
    uint vpl_end;
    uint pool;             // M camera points
    uint seed;             // the pool's seed (the batch's reverse VPLs')
    uint pixels;           // G-buffer texels
    float uncovered_scale;
    uint pool_begin;       // this dispatch's pool points
    uint pool_end;
} params;

void main() {
    uint slot = params.vpl_begin + gl_GlobalInvocationID.x;
    if (slot >= params.vpl_end) return;
    Vpl v = vpls[slot];
    if (vpl_kind(v) != VPL_SURFACE) return;
    bool first = params.pool_begin == 0u;
    bool last = params.pool_end >= params.pool;
    // Reached by an earlier dispatch's pool points.
    if (!first && v.incident.w == 0.0) return;
    vec3 n = v.normal.xyz;
    vec3 origin = offset_origin(v.position.xyz, n);
    if (pool_density(params.seed, params.pixels, params.pool, params.pool_begin,
                     params.pool_end, v.position.xyz, n, n, origin, true) > 0.0) {
        if (!first) {
            v.incident.w = 0.0;
            vpls[slot] = v;
        }
        return;
    }
    if (last) v.power.rgb *= params.uncovered_scale;
    v.incident.w = 1.0;
    vpls[slot] = v;
}
