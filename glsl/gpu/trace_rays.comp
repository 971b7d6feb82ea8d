#version 450
// Traces a buffer of rays through the BVH (bvh.glsl): the closest hit of each, or only whether
// anything is hit (push constant `mode`). The test and benchmark kernel of the traversal that
// every method includes (src/trace.rs is its wrapper).
#extension GL_GOOGLE_include_directive : require

#include "bvh.glsl"

layout(local_size_x = 64, local_size_y = 1, local_size_z = 1) in;

struct TraceRay {
    vec4 origin_t_max;  // xyz: origin; w: t_max (hits need 0 < t < t_max)
    vec4 direction;     // xyz: direction, any length; w unused
};
// Closest mode: t, GPU triangle and barycentrics, triangle BVH_NO_TRIANGLE on a miss.
// Any mode: triangle TRACE_ANY_HIT or BVH_NO_TRIANGLE, the rest zero.
struct TraceHit {
    float t;
    uint triangle;
    vec2 barycentrics;
};

layout(set = 0, binding = 2, std430) readonly buffer Rays { TraceRay rays[]; };
// TraceHit words; one uvec4 store (on lavapipe every buffer access is a loop over the lanes,
// so one store of 4 words beats three of 1, 1 and 2).
layout(set = 0, binding = 3, std430) writeonly buffer Hits { uvec4 hits[]; };

layout(push_constant) uniform TraceParams {
    uint ray_count;
    uint mode;  // 0: closest hit, 1: any hit
    // Times each ray is traced (0 counts as 1): more than 1 only in tests/bvh.rs, to spend
    // lavapipe's loop budget within one invocation and see the cut reported (bvh.glsl LoopCuts).
    uint repeat;
    uint _pad1;
} params;

#define TRACE_ANY_HIT 0xfffffffeu

void main() {
    // A 2D grid of workgroups, so ray counts past 65535 workgroups fit.
    uint i = gl_GlobalInvocationID.x + gl_GlobalInvocationID.y * gl_NumWorkGroups.x * 64u;
    if (i >= params.ray_count) {
        return;
    }
    vec4 origin_t_max = rays[i].origin_t_max;
    vec3 direction = rays[i].direction.xyz;
    TraceHit out_hit;
    uint r = 0u;
    do {
        if (params.mode == 0u) {
            RayHit hit;
            trace_closest(origin_t_max.xyz, direction, origin_t_max.w, hit);
            out_hit = TraceHit(hit.t, hit.triangle, hit.barycentrics);
            if (hit.triangle == BVH_NO_TRIANGLE) {
                out_hit.t = 0.0;
            }
        } else {
            bool any = trace_any(origin_t_max.xyz, direction, origin_t_max.w);
            out_hit = TraceHit(0.0, any ? TRACE_ANY_HIT : BVH_NO_TRIANGLE, vec2(0.0));
        }
    } while (++r < params.repeat);
    hits[i] = uvec4(floatBitsToUint(out_hit.t), out_hit.triangle,
                    floatBitsToUint(out_hit.barycentrics));
}
