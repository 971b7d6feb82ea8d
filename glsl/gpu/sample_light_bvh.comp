#version 450
// Selects a light through the light BVH (light_bvh.glsl) for each query (point p, normal n,
// random number u): the entry and pmf light_bvh_select returns, and the pmf light_bvh_pmf finds
// for that entry by re-walking its bit trail. The test kernel of the descent that the path
// tracer's next-event estimation runs: tests/light_bvh.rs compares its picks and pmfs with the
// CPU's f32 mirror (src/sampling/light_bvh.rs `LightBvh::sample` and `pmf`).
#extension GL_GOOGLE_include_directive : require

#include "scene.glsl"
#include "sampling.glsl"
#include "envmap.glsl"
#include "lights.glsl"
#include "light_bvh.glsl"

layout(local_size_x = 64, local_size_y = 1, local_size_z = 1) in;

struct LightQuery {
    vec4 p;  // xyz: the shading point; w: u in [0, 1)
    vec4 n;  // xyz: its normal (zero: none); w unused
};

layout(set = 0, binding = 10, std430) readonly buffer LightQueries { LightQuery queries[]; };
// Per query: (entry, bits of the select pmf, bits of the re-walked pmf, found 0 or 1); one
// uvec4 store.
layout(set = 0, binding = 11, std430) writeonly buffer LightPicks { uvec4 picks[]; };

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= uint(queries.length())) {
        return;
    }
    LightQuery q = queries[i];
    uint entry;
    float pmf;
    bool found = light_bvh_select(q.p.xyz, q.n.xyz, q.p.w, entry, pmf);
    float rewalked = found ? light_bvh_pmf(q.p.xyz, q.n.xyz, entry) : 0.0;
    picks[i] = uvec4(entry, floatBitsToUint(pmf), floatBitsToUint(rewalked), found ? 1u : 0u);
}
