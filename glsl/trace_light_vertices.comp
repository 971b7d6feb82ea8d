#version 450
// Tokuyoshi 12 Section 4.1: one VPL per iteration, from point and spot lights only. A light
// chosen by power (P_l, lights.glsl's table), a direction leaving it with its emission pdf
// (emission.glsl: 1 / (4 pi), or I(w) / integral of I for a spot), and the first surface the
// ray hits: x1; with it the iteration's bundle direction, computed here once instead of per
// pixel. One invocation per iteration of the frame; numbers in bundles.glsl.

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

layout(push_constant) uniform LightVertexParams {
    uint first_iteration;  // k of this frame's first iteration
    uint count;            // iterations per frame (I)
    uint seed;
} params;

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= params.count) return;
    uint k = params.first_iteration + i;
    float u[5];
    for (uint d = 0u; d < 5u; ++d) u[d] = halton(d, k, params.seed);

    LightVertex v;
    v.light = vec4(0.0);
    v.power = vec4(0.0);
    v.position = vec4(0.0);
    v.normal = vec4(0.0);
    v.side = vec4(0.0);
    // w_k, uniform on the sphere.
    float z = 1.0 - 2.0 * u[3];
    float s = sqrt(max(0.0, 1.0 - z * z));
    v.bundle = vec4(s * cos(2.0 * PI * u[4]), s * sin(2.0 * PI * u[4]), z, 0.0);
    if (scene.size.z == 0u) {
        light_vertices[i] = v;
        return;
    }
    uint r = min(uint(u[0] * 2147483648.0), 0x7fffffffu);
    LightEntry e = light_entries[select_light(r)];
    Light l = lights[e.index];
    vec3 x0 = l.position.xyz;
    vec3 w = sample_emission(l, vec2(u[1], u[2]));
    float pe = emission_pdf(l, w);
    v.light = vec4(x0, uintBitsToFloat(e.index));
    // I / p_e is the intensity's integral over the sphere whenever p_e follows I.
    v.power = vec4(pe > 0.0 ? l.intensity.rgb * (emission_profile(l, w) / (pe * e.probability))
                            : vec3(0.0),
                   e.probability);
    RayHit hit;
    if (pe > 0.0 && trace_closest(x0, w, infinity(), hit)) {
        vec3 x1 = x0 + hit.t * w;
        vec3 ng = shading_triangles[hit.triangle].geometric_normal.xyz;
        vec3 ns = shading_normal(hit.triangle, hit.barycentrics);
        vec3 side = dot(-w, ng) >= 0.0 ? ng : -ng;
        vec3 n = dot(ns, side) >= 0.0 ? ns : -ns;
        v.position = vec4(x1, 1.0);
        v.normal = vec4(n, uintBitsToFloat(triangle_material(hit.triangle)));
        v.side = vec4(side, pe * dot(side, -w) / (hit.t * hit.t));
    }
    light_vertices[i] = v;
}
