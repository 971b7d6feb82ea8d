#version 450
// Tokuyoshi 12 Section 4.1: the iteration's VPLs, from point and spot lights only, and its
// global ray bundle's direction (computed here once instead of per pixel). Light selection:
// one VPL from every light (the paper's default), or, for many lights, one light chosen by
// power (Russian roulette, LightEntries' table restricted to the point and spot lights, which
// come first in it). Each VPL leaves its light with the emission pdf (emission.glsl: 1 / (4 pi),
// or I(w) / integral of I for a spot) and lands on x1, the first surface its ray hits. The
// bundle direction is drawn from bundle_directions.glsl's density and stored with its p_r in
// every slot of the iteration. One invocation per (iteration, light slot) of the frame;
// numbers in bundles.glsl.

#extension GL_GOOGLE_include_directive : require

layout(local_size_x = 64, local_size_y = 1, local_size_z = 1) in;

#define BUNDLES_WRITE_LIGHT_VERTICES
#define BUNDLES_NO_HITS
#include "bvh.glsl"
#include "scene.glsl"
#include "sampling.glsl"
#include "halton.glsl"
#include "lights.glsl"
#include "emission.glsl"
#include "bundles.glsl"
#include "bundle_directions.glsl"

layout(push_constant) uniform LightVertexParams {
    uint first_iteration;  // k of this frame's first iteration
    uint count;            // iterations per frame (I)
    uint seed;
    uint lights;           // point and spot light entries, LightEntries' first
    uint slots;            // light vertices per iteration: `lights` (every light) or 1 (roulette)
    uint directions;       // BUNDLE_DIRECTIONS_UNIFORM or _ENVIRONMENT
} params;

void main() {
    uint slot = gl_GlobalInvocationID.x;
    uint slots = max(params.slots, 1u);
    uint i = slot / slots;
    uint v = slot % slots;
    if (i >= params.count) return;
    uint k = params.first_iteration + i;
    float u[7];
    for (uint d = 0u; d < 7u; ++d) u[d] = halton(d, k, params.seed);

    LightVertex lv;
    lv.light = vec4(0.0);
    lv.power = vec4(0.0);
    lv.position = vec4(0.0);
    lv.normal = vec4(0.0);
    lv.side = vec4(0.0);
    float p_r;
    vec3 w_k = sample_bundle_direction(params.directions, vec4(u[3], u[4], u[5], u[6]), p_r);
    lv.bundle = vec4(w_k, p_r);
    if (params.lights == 0u) {
        light_vertices[slot] = lv;
        return;
    }
    uint entry;
    float probability;
    if (params.slots > 1u || params.lights == 1u) {
        entry = v;
        probability = 1.0;
    } else {
        // Roulette: r uniform below the last point or spot light's upper bound (none when
        // the table's rounding left the lights no range next to the environment).
        uint bound = light_entries[params.lights - 1u].upper;
        if (bound == 0u) {
            light_vertices[slot] = lv;
            return;
        }
        uint r = min(uint(u[0] * float(bound)), bound - 1u);
        entry = select_light_among(r, params.lights);
        uint below = entry == 0u ? 0u : light_entries[entry - 1u].upper;
        probability = float(light_entries[entry].upper - below) / float(bound);
    }
    LightEntry e = light_entries[entry];
    Light l = lights[e.index];
    vec3 x0 = l.position.xyz;
    vec3 w = sample_emission(l, vec2(u[1], u[2]));
    float pe = emission_pdf(l, w);
    lv.light = vec4(x0, uintBitsToFloat(e.index));
    // I / p_e is the intensity's integral over the sphere whenever p_e follows I.
    lv.power = vec4(pe > 0.0 ? l.intensity.rgb * (emission_profile(l, w) / (pe * probability))
                             : vec3(0.0),
                    probability);
    RayHit hit;
    if (pe > 0.0 && trace_closest(x0, w, infinity(), hit)) {
        vec3 x1 = x0 + hit.t * w;
        vec3 ng = shading_triangles[hit.triangle].geometric_normal.xyz;
        vec3 ns = shading_normal(hit.triangle, hit.barycentrics);
        vec3 side = dot(-w, ng) >= 0.0 ? ng : -ng;
        vec3 n = dot(ns, side) >= 0.0 ? ns : -ns;
        lv.position = vec4(x1, 1.0);
        lv.normal = vec4(n, uintBitsToFloat(hit.triangle));
        lv.side = vec4(side, pe * dot(side, -w) / (hit.t * hit.t));
    }
    light_vertices[slot] = lv;
}
