#version 450
// The outgoing radiance of bir's reverse VPLs (Segovia 06 Section 3.1), with the paper's
// diffuse approximation L_o(x2) = Kd(x2) / pi * E(x2). As in the paper, "several paths are
// traced from a reverse VPL" and "standard VPLs are used instead of light paths": E(x2) is
// estimated, for each light path length exactly once, by
//   - light -> x2: next-event estimation at x2 (K samples);
//   - light -> x3 -> x2: K cosine-distributed directions from x2 to x3, next-event estimation
//     at x3 (one sample each), the full BSDF at x3;
//   - light -> ... -> v -> x3 -> x2: the same x3 connected to `connections` standard VPLs
//     of the frame drawn uniformly (with replacement) from its surface slots, each weighted by
//     slots / connections (one shadow ray each; all of them when connections is 0).
// Extending to x3 matters where standard VPLs starve near x2 but not one bounce further (the
// U office: x2 by room B's door, x3 in the corridor, the standard VPLs in room A); connecting
// x2 to standard VPLs directly as well would count those path lengths twice. A reverse VPL on
// a Phong surface loses its glossy reflection (the paper's approximation, kept: a named bias on
// glossy scenes). The VPL's power becomes pi L_o weight / (R p(x2)): as an area-kind VPL
// (cosine emitter, power / pi per unit of G) it adds f(x) L_o G V weight / (R p(x2)) at a
// shading point x, one term of Eq. 6's estimator.
//
// Numbers: PCG keyed by (seed, k, dimension).

#extension GL_GOOGLE_include_directive : require

layout(local_size_x = 64, local_size_y = 1, local_size_z = 1) in;

#define REVERSE_VPL_WRITE
#include "bvh.glsl"
#include "scene.glsl"
#include "sampling.glsl"
#include "bsdf.glsl"
#include "lights.glsl"
#include "vpl.glsl"
#include "vpl_shading.glsl"
#include "reverse_vpl.glsl"

layout(push_constant) uniform ShadeParams {
    uint count;          // R reverse VPLs
    uint light_samples;  // next-event samples per reverse VPL
    uint vpl_begin;      // standard VPL slots [vpl_begin, vpl_end) light the reverse VPLs
    uint vpl_end;
    uint seed;
    float weight;        // bir's share of the reverse side (1/2 when both sides are shaded)
    uint connections;    // standard VPLs per x3 (0: every one)
} params;

// One next-event sample at x (offset already) with material m seen from wo: f cos L / pdf.
vec3 next_event(vec3 x, vec3 n, vec3 side, vec3 wo, Material m, uint k, uint dim) {
    LightSample ls;
    uint r_select = random_u31(params.seed, k, 0x73686164u, dim);
    uint r_texel = random_u31(params.seed, k, 0x73686164u, dim + 1u);
    vec2 u = vec2(random(params.seed, k, 0x73686164u, dim + 2u),
                  random(params.seed, k, 0x73686164u, dim + 3u));
    if (!sample_light(x, r_select, r_texel, u, ls)) return vec3(0.0);
    float cos_i = dot(ls.direction, n);
    if (cos_i <= 0.0 || dot(ls.direction, side) <= 0.0) return vec3(0.0);
    vec3 f = bsdf_eval(m, n, wo, ls.direction);
    if (max(max(f.r, f.g), f.b) <= 0.0) return vec3(0.0);
    bool visible = isinf(ls.distance) ? !trace_any(x, ls.direction, infinity())
                                      : !trace_any(x, ls.direction * ls.distance, 0.9999);
    return visible ? f * cos_i * ls.radiance / ls.pdf : vec3(0.0);
}

void main() {
    uint k = gl_GlobalInvocationID.x;
    if (k >= params.count) return;
    Vpl v = reverse_vpls[k];
    if (vpl_kind(v) == VPL_NONE) return;

    vec3 x = v.position.xyz;      // already off the surface
    vec3 n = v.normal.xyz;
    vec3 side = v.incident.xyz;
    Material m = materials[floatBitsToUint(v.normal.w)];
    vec3 kd = m.kd.rgb;
    // Diffuse approximation: the Lambert part alone.
    m.kd.w = 0.0;
    m.ks = vec4(0.0);

    uint samples = max(params.light_samples, 1u);
    // light -> x2: Kd / pi cos L / pdf.
    vec3 radiance = vec3(0.0);
    for (uint j = 0u; j < samples; ++j) {
        radiance += next_event(x, n, side, n, m, k, 8u * j) / float(samples);
    }
    // light -> x3 -> x2 and light -> ... -> v -> x3 -> x2: x3 by cosine sampling, whose pdf
    // cancels Kd / pi cos to Kd.
    for (uint j = 0u; j < samples; ++j) {
        vec2 u = vec2(random(params.seed, k, 0x73686164u, 8u * j + 4u),
                      random(params.seed, k, 0x73686164u, 8u * j + 5u));
        vec3 w = to_world(sample_cosine_hemisphere(u), n);
        RayHit hit;
        if (dot(w, side) <= 0.0 || !trace_closest(x, w, infinity(), hit)) continue;
        vec3 x3 = x + hit.t * w;
        vec3 ng3 = shading_triangles[hit.triangle].geometric_normal.xyz;
        vec3 wo3 = -w;
        vec3 side3 = dot(wo3, ng3) >= 0.0 ? ng3 : -ng3;
        vec3 ns3 = shading_normal(hit.triangle, hit.barycentrics);
        vec3 n3 = dot(ns3, side3) >= 0.0 ? ns3 : -ns3;
        vec3 o3 = offset_origin(x3, side3);
        Material m3 = materials[triangle_material(hit.triangle)];
        vec3 incoming = next_event(o3, n3, side3, wo3, m3, k, 8u * j + 6u);
        uint slots = params.vpl_end - params.vpl_begin;
        if (params.connections == 0u || params.connections >= slots) {
            for (uint s = params.vpl_begin; s < params.vpl_end; ++s) {
                incoming += shade_from_vpl(vpls[s], x3, o3, n3, side3, wo3, m3, 0.0);
            }
        } else {
            vec3 sum = vec3(0.0);
            for (uint c = 0u; c < params.connections; ++c) {
                uint pick = random_u31(params.seed, k, 0x636f6e6eu, j * 4096u + c) % slots;
                sum += shade_from_vpl(vpls[params.vpl_begin + pick], x3, o3, n3, side3, wo3, m3, 0.0);
            }
            incoming += sum * (float(slots) / float(params.connections));
        }
        radiance += kd * incoming / float(samples);
    }

    v.power.rgb = radiance * (PI * params.weight / (float(params.count) * v.power.w));
    reverse_vpls[k] = v;
}
