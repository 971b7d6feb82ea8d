#version 450
// The outgoing radiance of bir's reverse VPLs (Segovia 06 Section 3.1), with the paper's
// diffuse approximation L_o(x2) = Kd(x2) / pi * E(x2). As in the paper, "several paths are
// traced from a reverse VPL" and "standard VPLs are used instead of light paths": K paths
// leave x2 (cosine-distributed, then by the BSDF) for `depth` vertices x3, x4, ...; every
// light path length is counted exactly once:
//   - light -> x2, light -> x3 -> x2, ...: next-event estimation at x2 (K samples) and at
//     every path vertex (one sample each), the full BSDF at the path vertices;
//   - light -> ... -> v -> x_last -> ... -> x2: the path's last vertex connected to the
//     frame's standard VPLs v (surface VPLs; `connections` of them drawn uniformly and
//     weighted, or all; one shadow ray each).
// Going a few vertices on matters where standard VPLs starve near x2 but not further away
// (the U office: x2 by room B's door, the standard VPLs in room A). A reverse VPL on a Phong
// surface loses its glossy reflection (the paper's approximation, kept: a named bias on
// glossy scenes). The VPL's power becomes pi L_o weight / (R p(x2)): as an area-kind VPL
// (cosine emitter, power / pi per unit of G) it adds f(x) L_o G V weight / (R p(x2)) at a
// shading point x, one term of Eq. 6's estimator.
//
// Numbers: PCG keyed by (seed, k, dimension).
//
// Split over dispatches: a dispatch takes samples [sample_begin, sample_end) and, of each
// path's connections (the standard VPL slots, or the drawn ones), [connection_begin,
// connection_end); the next-event terms are taken where connection_begin is 0, and the path
// is traced again for each later range of its connections (the same random numbers, the same
// vertices). The first dispatch writes the power, the others add theirs. lavapipe stops an
// invocation's loops silently after 65535 iterations in all (docs/DESIGN.md "The loop budget"), and each
// next event and connection is a shadow ray's traversal loop: unsplit, 1024 light samples
// came out 8.5% dark under --strategy reverse on the Cornell box (32x32, 4 frames), and a
// frame of 2^20 VPLs connected each path to half a million slots in one invocation.
//
// bir's --reverse-history H: the radiance also connects to the standard VPLs of the H - 1
// batches before (a still's earlier frames), each batch's set an unbiased estimate of the same
// light, so each set's connections weigh vpl_weight = 1 / (sets used); a dispatch with
// history = 1 adds one earlier set's connections only (no next events, never the first write).

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
    uint connections;    // standard VPLs per path end (0: every one)
    uint depth;          // path vertices after x2
    uint sample_begin;   // this dispatch's samples
    uint sample_end;
    uint connection_begin;  // and its range of each path's connections
    uint connection_end;
    float vpl_weight;    // the connections' weight: 1 / the standard VPL sets connected to
    uint history;        // 1: an earlier batch's set, its connections added to the power
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
    uint mat = floatBitsToUint(v.normal.w);
    Material m = textured(materials[mat], mat, floatBitsToUint(v.incident.w), x);
    vec3 kd = m.kd.rgb;
    // Diffuse approximation: the Lambert part alone.
    m.kd.w = 0.0;
    m.ks = vec4(0.0);

    uint samples = max(params.light_samples, 1u);
    uint sample_end = min(params.sample_end, samples);
    bool next_events = params.connection_begin == 0u && params.history == 0u;
    // light -> x2: Kd / pi cos L / pdf.
    vec3 radiance = vec3(0.0);
    for (uint j = params.sample_begin; next_events && j < sample_end; ++j) {
        radiance += next_event(x, n, side, n, m, k, 8u * j) / float(samples);
    }
    // The paths from x2: cosine-distributed first (its pdf cancels Kd / pi cos to Kd).
    for (uint j = params.sample_begin; j < sample_end; ++j) {
        uint dim = 64u * (j + 1u);
        vec2 u = vec2(random(params.seed, k, 0x73686164u, dim),
                      random(params.seed, k, 0x73686164u, dim + 1u));
        vec3 w = to_world(sample_cosine_hemisphere(u), n);
        if (dot(w, side) <= 0.0) continue;
        vec3 beta = kd;
        vec3 origin = x;
        vec3 incoming = vec3(0.0);
        for (uint d = 1u; d <= params.depth; ++d) {
            RayHit hit;
            if (!trace_closest(origin, w, infinity(), hit)) break;
            vec3 xd = origin + hit.t * w;
            vec3 ngd = shading_triangles[hit.triangle].geometric_normal.xyz;
            vec3 wod = -w;
            vec3 sided = dot(wod, ngd) >= 0.0 ? ngd : -ngd;
            vec3 nsd = shading_normal(hit.triangle, hit.barycentrics);
            vec3 nd = dot(nsd, sided) >= 0.0 ? nsd : -nsd;
            vec3 od = offset_origin(xd, sided);
            Material md = surface_material(hit.triangle, xd);
            if (next_events) {
                incoming += beta * next_event(od, nd, sided, wod, md, k, dim + 2u + 8u * d);
            }
            if (d == params.depth) {
                uint slots = params.vpl_end - params.vpl_begin;
                vec3 sum = vec3(0.0);
                if (params.connections == 0u || params.connections >= slots) {
                    uint end = params.vpl_begin + min(params.connection_end, slots);
                    for (uint s = params.vpl_begin + min(params.connection_begin, slots); s < end;
                         ++s) {
                        Vpl source = vpls[s];
                        sum += shade_from_vpl(source, vpl_material(source), xd, od, nd, sided, wod, md,
                                              0.0);
                    }
                } else {
                    uint end = min(params.connection_end, params.connections);
                    for (uint c = params.connection_begin; c < end; ++c) {
                        // Sample and connection keyed apart: no two share picks at any count.
                        uint pick = random_u31(params.seed, k, 0x636f6e6eu + j, c) % slots;
                        Vpl source = vpls[params.vpl_begin + pick];
                        sum += shade_from_vpl(source, vpl_material(source), xd, od, nd, sided, wod, md,
                                              0.0);
                    }
                    sum *= float(slots) / float(params.connections);
                }
                incoming += beta * (sum * params.vpl_weight);
                break;
            }
            vec3 ub = vec3(random(params.seed, k, 0x73686164u, dim + 6u + 8u * d),
                           random(params.seed, k, 0x73686164u, dim + 7u + 8u * d),
                           random(params.seed, k, 0x73686164u, dim + 8u + 8u * d));
            vec3 wi;
            if (!bsdf_sample(md, nd, wod, ub, wi)) break;
            float pdf = bsdf_pdf(md, nd, wod, wi);
            float cos_i = dot(wi, nd);
            if (pdf <= 0.0 || cos_i <= 0.0 || dot(wi, sided) <= 0.0) break;
            beta *= bsdf_eval(md, nd, wod, wi) * (cos_i / pdf);
            origin = od;
            w = wi;
        }
        radiance += incoming / float(samples);
    }

    vec3 power = radiance * (PI * params.weight / (float(params.count) * v.power.w));
    bool first =
        params.sample_begin == 0u && params.connection_begin == 0u && params.history == 0u;
    v.power.rgb = first ? power : v.power.rgb + power;
    reverse_vpls[k] = v;
}
