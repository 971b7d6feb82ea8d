#version 450
// Tokuyoshi 12 Sections 3.3 and 4.2-4.3: light at each G-buffer point x3 from the chunk's
// iterations. Direct light of the environment map: the point's bundle ray that escapes, Le
// over the bundle density p_r (Fig. 6; Eq. 2's pdf or uniform). One-bounce: the VPL path
// (x0, x1, x3) and the bundle path (x0, x2, x3), x2 the point's bundle hit lit by next-event
// estimation from the light vertex's light, combined by the power heuristic with exponent beta
// (1: the balance heuristic, Eq. 6) over the area densities of Eq. 4-5, p1 = p_e(w01) |cos| /
// d01^2 and p2 = p_r |cos| / d^2 (the light's selection probability is common to both and
// cancels). Two-bounce: (x0, x1, x2, x3) through the edge x1-x2 (Eq. 7-8; its geometry term
// optionally clamped, the paper's bias, and by default compensated: below). Strategy 0 shades the VPL paths alone, 1 the bundle
// paths alone (weight 1 each), 2 both with MIS. Each iteration has `slots` light vertices
// (one per light, or one chosen by roulette) sharing one bundle. The frame's estimate is the
// mean over its I iterations; each chunk adds its share.
//
// The clamp's compensation (Kollig and Keller 2004, as include/compensation.glsl for the VPL
// gathers): the clamp removes (G - b)+ of the x1-x2 edge wherever x1 lies near x2. Per
// iteration, a BSDF-sampled direction from x2 finds y; where the edge's G(x2, y) (as the
// two-bounce term computes it for x1 = y) exceeds b, y stands in for x1: the iteration's lights
// light y directly (one shadow ray each, over each slot's selection probability, as its light
// vertices were drawn), weighted f2 cos / pdf (1 - b / G). Bundles' paths end at two bounces,
// so one level and no recursion: clamped term plus compensation is the unclamped term's
// expectation. Random numbers: PCG keyed by (seed, pixel, iteration of the render, dimension).
//
// A chunk is shaded in dispatches of a few iterations (`hit_first` the first's place among the
// chunk's bundle hits): each iteration casts about four shadow rays per light vertex, each a
// traversal loop, and lavapipe stops an invocation's loops silently after 65535 iterations in
// all (docs/DESIGN.md "The loop budget").

#extension GL_GOOGLE_include_directive : require

layout(local_size_x = 8, local_size_y = 8, local_size_z = 1) in;

#include "bvh.glsl"
#include "scene.glsl"
#include "sampling.glsl"
#include "bsdf.glsl"
#include "lights.glsl"
#include "emission.glsl"
#include "gbuffer.glsl"
#include "radiance.glsl"
#include "bundles.glsl"
#include "roughness_clamp.glsl"
#include "bundle_directions.glsl"

layout(push_constant) uniform ShadeParams {
    uint first_index;      // the chunk's first iteration of the frame
    uint count;            // iterations in the chunk
    uint per_frame;        // I
    uint strategy;         // 0 vpl, 1 bundle, 2 mis
    float beta;            // power heuristic exponent (1: balance)
    float two_bounce;      // < 0: off; 0: unclamped; > 0: clamp of the x1-x2 geometry term
    uint samples;          // N: iterations in the whole render (the sample count of Eq. 14-16)
    uint suppression;      // glossy spike suppression of the one-bounce paths: 0 none,
                           // 1 roughness clamping (Section 5), 2 plain contribution clamping
    float suppression_parameter;  // roughness: m'; contribution: the largest channel allowed
    uint slots;            // light vertices per iteration
    uint directions;       // the bundles' density (bundle_directions.glsl)
    uint environment;      // 1: add the environment's direct light through the bundles
    uint trace_bundles;    // 0: no bundle hits were traced (VPL paths alone)
    uint frame_first;      // the frame's first iteration of the render (frame * I)
    uint seed;
    uint compensate;       // 1: compensate the two-bounce clamp (two_bounce > 0)
    uint hit_first;        // bundle_hits' iteration of first_index (the chunk's from 0)
} params;

#define STRATEGY_VPL 0u
#define STRATEGY_BUNDLE 1u
#define STRATEGY_MIS 2u
#define SUPPRESS_ROUGHNESS 1u
#define SUPPRESS_CONTRIBUTION 2u

float mis_weight(float p_this, float p_other) {
    if (params.strategy != STRATEGY_MIS) return 1.0;
    if (params.beta == 1.0) return p_this / (p_this + p_other);
    float a = pow(p_this, params.beta);
    float b = pow(p_other, params.beta);
    return a / (a + b);
}

bool any_positive(vec3 c) {
    return max(max(c.r, c.g), c.b) > 0.0;
}

// Section 5.2: the solid-angle densities of the samples through x_j, Eq. 15-16: N times the
// area density with which the strategies in use sample x_j (p1 + p2 under MIS; times the
// light's selection probability under roulette), seen from x0 (dist0^2 / cos0 at x_j) and from
// x3 (dist3^2 / cos3).
void edge_densities(float p_this, float p_other, float selection, float dist0_2, float cos0,
                    float dist3_2, float cos3, out float d_j0, out float d_j3) {
    float area = float(params.samples) * selection *
                 (params.strategy == STRATEGY_MIS ? p_this + p_other : p_this);
    d_j0 = area * dist0_2 / cos0;
    d_j3 = area * dist3_2 / cos3;
}

// Plain clamping (the baseline of Section 5): the largest channel of a path's weighted
// contribution at most the parameter.
vec3 clamp_contribution(vec3 c) {
    if (params.suppression != SUPPRESS_CONTRIBUTION) return c;
    float peak = max(max(c.r, c.g), c.b);
    return peak > params.suppression_parameter ? c * (params.suppression_parameter / peak) : c;
}

// The two-bounce clamp's compensation at x2 for iteration k (its light vertices at `base`).
vec3 two_bounce_compensation(uint index, uint k, uint base, vec3 x2, vec3 n2, vec3 side2,
                             vec3 wo2, Material m2, vec3 origin2) {
    float b = params.two_bounce;
    vec3 u = vec3(random(params.seed, index, k, 0u), random(params.seed, index, k, 1u),
                  random(params.seed, index, k, 2u));
    vec3 wi;
    if (!bsdf_sample(m2, n2, wo2, u, wi)) return vec3(0.0);
    float pdf = bsdf_pdf(m2, n2, wo2, wi);
    float cos_i = dot(wi, n2);
    if (pdf <= 0.0 || cos_i <= 0.0 || dot(wi, side2) <= 0.0) return vec3(0.0);
    // G > b needs |y - x2|^2 < 1 / b: a short ray (trace_compensation_paths.comp).
    RayHit hit;
    if (!trace_closest(origin2, wi, inversesqrt(b) + 2.0 * distance(origin2, x2), hit)) {
        return vec3(0.0);
    }
    vec3 y = origin2 + hit.t * wi;
    vec3 e = y - x2;
    float dist2 = dot(e, e);
    if (!(dist2 > 0.0)) return vec3(0.0);
    vec3 w = e * inversesqrt(dist2);
    vec3 ng_y = shading_triangles[hit.triangle].geometric_normal.xyz;
    vec3 ns_y = shading_normal(hit.triangle, hit.barycentrics);
    vec3 side_y = dot(-wi, ng_y) >= 0.0 ? ng_y : -ng_y;
    vec3 n_y = dot(ns_y, side_y) >= 0.0 ? ns_y : -ns_y;
    float g = max(dot(n2, w), 0.0) * max(dot(n_y, -w), 0.0) / dist2;
    if (!(g > b)) return vec3(0.0);
    vec3 weight = bsdf_eval(m2, n2, wo2, wi) * (cos_i / pdf) * (1.0 - b / g);
    if (!any_positive(weight)) return vec3(0.0);
    Material my = surface_material(hit.triangle, y);
    vec3 origin_y = offset_origin(y, side_y);
    vec3 direct = vec3(0.0);
    // Do-whiles (slots and count are at least 1): gallivm tests a loop's lanes at the end of
    // its body, so a test at the top costs one more whole body, masked (bvh.glsl).
    uint s = 0u;
    do {
        LightVertex lv = light_vertices[base + s];
        ++s;
        if (lv.power.w <= 0.0) continue;
        Light l = lights[floatBitsToUint(lv.light.w)];
        vec3 to_light = l.position.xyz - y;
        float d2 = dot(to_light, to_light);
        if (!(d2 > 0.0)) continue;
        vec3 wl = to_light * inversesqrt(d2);
        float cos_l = dot(wl, n_y);
        if (cos_l <= 0.0 || dot(wl, side_y) <= 0.0) continue;
        vec3 c = bsdf_eval(my, n_y, -wi, wl) * l.intensity.rgb *
                 (emission_profile(l, -wl) * cos_l / (d2 * lv.power.w));
        if (any_positive(c) && !trace_any(origin_y, l.position.xyz - origin_y, 0.9999)) {
            direct += c;
        }
    } while (s < params.slots);
    return weight * direct;
}

void main() {
    uvec2 pixel = gl_GlobalInvocationID.xy;
    if (pixel.x >= scene.size.x || pixel.y >= scene.size.y) return;
    uint index = pixel.y * scene.size.x + pixel.x;
    uint pixels = scene.size.x * scene.size.y;
    GBufferTexel g = gbuffer[index];
    vec3 wo3, side3, n3;
    if (!gbuffer_surface(g, wo3, side3, n3)) return;
    vec3 x3 = g.position.xyz;
    vec3 origin3 = offset_origin(x3, side3);
    Material m3 = gbuffer_material(g);
    float m_prime = params.suppression_parameter;

    vec3 sum = vec3(0.0);
    if (params.count == 0u || params.slots == 0u) return;
    uint j = 0u;
    do {
        uint base = (params.first_index + j) * params.slots;
        vec4 bundle = light_vertices[base].bundle;
        // The point's bundle ray, its density, and what it hit.
        vec3 d = bundle_ray(bundle.xyz, side3);
        float p_r = bundle.w;
        float cos3 = dot(n3, d);
        bool has_x2 = false;
        vec3 f3, x2, n2, side2, origin2;
        float t, cos2g_3;
        Material m2;
        if (params.trace_bundles != 0u && cos3 > 0.0 && p_r > 0.0) {
            f3 = bsdf_eval(m3, n3, wo3, d);
            BundleHit h = bundle_hits[(params.hit_first + j) * pixels + index];
            if (h.position.w < 0.0) {
                // Escaped: the environment's direct light (Eq. 14: d_3 = N p_r).
                if (params.environment != 0u) {
                    vec3 le = env_radiance(d);
                    vec3 f = f3;
                    if (params.suppression == SUPPRESS_ROUGHNESS) {
                        float density = float(params.samples) * p_r;
                        f = bsdf_eval(clamp_roughness(m3, density, cos3, m_prime), n3, wo3, d);
                    }
                    vec3 c = le * f * (cos3 / p_r);
                    if (any_positive(c)) sum += clamp_contribution(c);
                }
            } else if (any_positive(f3)) {
                has_x2 = true;
                x2 = h.position.xyz;
                t = h.position.w;
                uint tri = h.triangle.x;
                vec3 ng2 = shading_triangles[tri].geometric_normal.xyz;
                vec3 ns2 = shading_normal(tri, vec2(uintBitsToFloat(h.triangle.y),
                                                    uintBitsToFloat(h.triangle.z)));
                side2 = dot(-d, ng2) >= 0.0 ? ng2 : -ng2;
                n2 = dot(ns2, side2) >= 0.0 ? ns2 : -ns2;
                m2 = surface_material(tri, x2);
                origin2 = offset_origin(x2, side2);
                cos2g_3 = -dot(side2, d);  // at x2, toward x3
            }
        }

        if (has_x2 && params.two_bounce > 0.0 && params.compensate != 0u) {
            sum += f3 * (cos3 / p_r) *
                   two_bounce_compensation(index, params.frame_first + params.first_index + j,
                                           base, x2, n2, side2, -d, m2, origin2);
        }

        uint s = 0u;
        do {
            LightVertex lv = light_vertices[base + s];
            ++s;
            if (lv.power.w <= 0.0) continue;
            Light l = lights[floatBitsToUint(lv.light.w)];
            vec3 x0 = lv.light.xyz;
            bool has_x1 = lv.position.w > 0.0;
            vec3 x1 = lv.position.xyz;
            vec3 n1 = lv.normal.xyz;
            vec3 side1 = lv.side.xyz;
            vec3 w10 = normalize(x0 - x1);
            // Triangle 0's material where the ray from x0 missed (unused: has_x1 is false).
            Material m1 = surface_material(has_x1 ? floatBitsToUint(lv.normal.w) : 0u, x1);

            // One bounce through the VPL x1.
            if (has_x1 && params.strategy != STRATEGY_BUNDLE) {
                vec3 e = x1 - x3;
                float dist2 = dot(e, e);
                vec3 w31 = e * inversesqrt(max(dist2, 1e-30));
                float cos3v = dot(n3, w31);
                float cos1 = -dot(n1, w31);
                float cos1g = -dot(side1, w31);
                if (dist2 > 0.0 && cos3v > 0.0 && dot(side3, w31) > 0.0 && cos1 > 0.0 &&
                    cos1g > 0.0) {
                    float p1 = lv.side.w;
                    float p2 = bundle_pdf(params.directions, w31) * cos1g / dist2;
                    Material m1s = m1;
                    Material m3s = m3;
                    if (params.suppression == SUPPRESS_ROUGHNESS) {
                        vec3 e0 = x0 - x1;
                        float d_j0, d_j3;
                        edge_densities(p1, p2, lv.power.w, dot(e0, e0), dot(side1, w10), dist2,
                                       cos1g, d_j0, d_j3);
                        m1s = clamp_roughness(m1, combine_densities(d_j0, d_j3), dot(n1, w10),
                                              m_prime);
                        m3s = clamp_roughness(m3, d_j3, cos3v, m_prime);
                    }
                    vec3 c = lv.power.rgb * bsdf_eval(m1s, n1, w10, -w31) *
                             bsdf_eval(m3s, n3, wo3, w31) * (cos1 * cos3v / dist2);
                    if (any_positive(c)) {
                        vec3 target = offset_origin(x1, side1);
                        if (!trace_any(origin3, target - origin3, 0.9999)) {
                            sum += clamp_contribution(c * mis_weight(p1, p2));
                        }
                    }
                }
            }
            if (!has_x2) continue;

            // One bounce through the bundle hit x2, lit by the vertex's light.
            if (params.strategy != STRATEGY_VPL) {
                vec3 e = x0 - x2;
                float dist2 = dot(e, e);
                vec3 w20 = e * inversesqrt(max(dist2, 1e-30));
                float cos2 = dot(n2, w20);
                float cos2g = dot(side2, w20);
                if (dist2 > 0.0 && cos2 > 0.0 && cos2g > 0.0) {
                    float p1 = emission_pdf(l, -w20) * cos2g / dist2;
                    float p2 = p_r * cos2g_3 / (t * t);
                    Material m2s = m2;
                    vec3 f3s = f3;
                    if (params.suppression == SUPPRESS_ROUGHNESS) {
                        float d_j0, d_j3;
                        edge_densities(p2, p1, lv.power.w, dist2, cos2g, t * t, cos2g_3, d_j0,
                                       d_j3);
                        m2s = clamp_roughness(m2, combine_densities(d_j0, d_j3), cos2, m_prime);
                        f3s = bsdf_eval(clamp_roughness(m3, d_j3, cos3, m_prime), n3, wo3, d);
                    }
                    float profile = emission_profile(l, -w20);
                    vec3 c = l.intensity.rgb * (profile * cos2 / (dist2 * lv.power.w * p_r))
                             * bsdf_eval(m2s, n2, -d, w20) * f3s * cos3;
                    if (any_positive(c) && !trace_any(origin2, x0 - origin2, 0.9999)) {
                        sum += clamp_contribution(c * mis_weight(p2, p1));
                    }
                }
            }

            // Two bounces: x0 -> x1 -> x2 -> x3, the only strategy that samples these paths.
            if (params.two_bounce >= 0.0 && has_x1) {
                vec3 e = x2 - x1;
                float dist2 = dot(e, e);
                vec3 w12 = e * inversesqrt(max(dist2, 1e-30));
                float cos1 = dot(n1, w12);
                float cos2 = -dot(n2, w12);
                if (dist2 > 0.0 && cos1 > 0.0 && dot(side1, w12) > 0.0 && cos2 > 0.0 &&
                    -dot(side2, w12) > 0.0) {
                    float g12 = cos1 * cos2 / dist2;
                    if (params.two_bounce > 0.0) g12 = min(g12, params.two_bounce);
                    vec3 c = lv.power.rgb * bsdf_eval(m1, n1, w10, w12) *
                             bsdf_eval(m2, n2, -d, -w12) * f3 * (g12 * cos3 / p_r);
                    if (any_positive(c)) {
                        vec3 target = offset_origin(x1, side1);
                        if (!trace_any(origin2, target - origin2, 0.9999)) sum += c;
                    }
                }
            }
        } while (s < params.slots);
        ++j;
    } while (j < params.count);
    accumulate_radiance(index, sum / float(params.per_frame));
}
