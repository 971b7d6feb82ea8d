#version 450
// The `env` method's shading (Lu 14 Section 3.3, Alg. 2), direct light of the environment map
// with visibility (a shadow ray per sample), at each G-buffer point p with shading normal n.
// Light samples come from the frame's pre-generated per-face samples (EnvSamples, shared by
// every pixel); the radiance is always the scene's own map (envmap.glsl), the cube map only
// drives the pdf. Strategies:
//   dynamic (0): mu_f(n) = F_f(n) I_f / sum_g F_g(n) I_g (Eq. 3.4), F_f(n) the sum of
//     <n, c>+ over the face's normalized corners; N_s / 2 light samples split over the faces
//     as fractional counts M_f = mu_f N_s / 2 with the beta weights (Eq. 3.5-3.6), and N_s / 2
//     BRDF samples, combined by the balance heuristic (Eq. 3.7):
//       g = s / (mu_f pdf_L(w | f) / 2 + pdf_B(w) / 2),
//       h = s / (mu_face(w) pdf_L(w | face(w)) / 2 + pdf_B(w) / 2),
//     L = (sum of beta g + sum of beta h) / N_s, unbiased whatever the split (N_L = N_B).
//     With light_share 1 (light only): all N_s from the faces, g = s / (mu_f pdf_L) (Eq. 3.5).
//   uniform-faces (1): the same with mu_f = 1/6 (the thesis's comparison).
//   latlong (4): N_s / 2 light samples per pixel from one table over the whole
//     equirectangular map (luminance times solid angle: the pbrt/Mitsuba sampler,
//     equirect_table.glsl), random per pixel, and N_s / 2 BRDF samples, balance heuristic.
//   brdf (2): N_s BRDF samples, s / pdf_B.
//   cosine (3): N_s cosine-weighted directions about n, s / (cos / pi).
// BRDF and cosine samples are random per pixel (seed, pixel, sample).

#extension GL_GOOGLE_include_directive : require

layout(local_size_x = 8, local_size_y = 8, local_size_z = 1) in;

#include "bvh.glsl"
#include "scene.glsl"
#include "sampling.glsl"
#include "bsdf.glsl"
#include "envmap.glsl"
#include "gbuffer.glsl"
#include "radiance.glsl"
#include "cubemap.glsl"
#include "env_cube.glsl"
#include "equirect_table.glsl"

layout(set = 0, binding = 24, std430) readonly buffer EnvSamples { vec4 env_samples[]; };
// Per pixel, summed over frames: x the light samples used (their beta weights), y those that
// are effective (above the surface: not cancelled by the cosine; Lu Fig. 3.6).
layout(set = 0, binding = 25, std430) buffer EnvSampleCounts { vec2 env_sample_counts[]; };

layout(push_constant) uniform ShadeParams {
    uint resolution;  // R
    uint per_face;    // pre-generated samples per face (at least N_s / 2)
    uint strategy;
    float spp;        // N_s
    uint frame;
    uint seed;
    float light_share;  // dynamic and uniform-faces: the share of N_s taken by light samples,
                        // 1/2 (Eq. 3.7, with BRDF samples) or 1 (light only, Eq. 3.5)
    uint integer_counts;  // 1: round(M_f) samples per face instead of beta-weighted M_f
} params;

#define STRATEGY_DYNAMIC 0u
#define STRATEGY_UNIFORM_FACES 1u
#define STRATEGY_BRDF 2u
#define STRATEGY_COSINE 3u
#define STRATEGY_LATLONG 4u

// mu_f(n) for every face (Eq. 3.4), or 1/6 each.
void face_shares(vec3 n, out float mu[6]) {
    if (params.strategy == STRATEGY_UNIFORM_FACES) {
        for (uint f = 0u; f < 6u; ++f) mu[f] = 1.0 / 6.0;
        return;
    }
    float sum = 0.0;
    for (uint f = 0u; f < 6u; ++f) {
        float form = 0.0;
        for (uint c = 0u; c < 4u; ++c) {
            vec3 corner = normalize(cube_face_point(f, (c & 1u) != 0u ? 1.0 : -1.0,
                                                    (c & 2u) != 0u ? 1.0 : -1.0));
            form += max(dot(n, corner), 0.0);
        }
        mu[f] = form * cube_face_totals[f];
        sum += mu[f];
    }
    for (uint f = 0u; f < 6u; ++f) mu[f] = sum > 0.0 ? mu[f] / sum : 0.0;
}

// s(p, o, w) without visibility: BRDF times cosine times the map's radiance; zero below the
// surface (shading and geometric sides).
vec3 integrand(Material m, vec3 n, vec3 side, vec3 wo, vec3 wi) {
    float c = dot(n, wi);
    if (c <= 0.0 || dot(side, wi) <= 0.0) return vec3(0.0);
    return bsdf_eval(m, n, wo, wi) * c * env_radiance(wi);
}

bool visible(vec3 origin, vec3 wi) {
    return !trace_any(origin, wi, infinity());
}

void main() {
    uvec2 pixel = gl_GlobalInvocationID.xy;
    if (pixel.x >= scene.size.x || pixel.y >= scene.size.y) return;
    uint index = pixel.y * scene.size.x + pixel.x;
    GBufferTexel g = gbuffer[index];
    vec3 wo, side, n;
    if (!gbuffer_surface(g, wo, side, n)) return;
    Material m = materials[floatBitsToUint(g.shading_normal.w)];
    vec3 origin = offset_origin(g.position.xyz, side);
    uint r = params.resolution;
    float ns = params.spp;
    vec3 sum = vec3(0.0);

    if (params.strategy == STRATEGY_BRDF || params.strategy == STRATEGY_COSINE) {
        uint count = uint(ns);
        for (uint k = 0u; k < count; ++k) {
            uint sample_index = params.frame * count + k;
            vec3 u = vec3(random(params.seed, index, sample_index, 0u),
                          random(params.seed, index, sample_index, 1u),
                          random(params.seed, index, sample_index, 2u));
            vec3 wi;
            float pdf;
            if (params.strategy == STRATEGY_BRDF) {
                if (!bsdf_sample(m, n, wo, u, wi)) continue;
                pdf = bsdf_pdf(m, n, wo, wi);
            } else {
                wi = to_world(sample_cosine_hemisphere(u.xy), n);
                pdf = max(dot(n, wi), 0.0) * INV_PI;
            }
            if (!(pdf > 0.0)) continue;
            vec3 s = integrand(m, n, side, wo, wi);
            if (max(max(s.r, s.g), s.b) > 0.0 && visible(origin, wi)) sum += s / pdf;
        }
        accumulate_radiance(index, sum / max(float(count), 1.0));
        return;
    }

    float half_count = 0.5 * ns;
    vec2 counts = vec2(0.0);
    uint whole = uint(ceil(half_count));

    if (params.strategy == STRATEGY_LATLONG) {
        for (uint i = 0u; i < whole && !equirect_table_empty(); ++i) {
            float beta = min(1.0, half_count - float(i));
            uint sample_index = params.frame * whole + i;
            vec4 u = vec4(random(params.seed, index, sample_index, 3u),
                          random(params.seed, index, sample_index, 4u),
                          random(params.seed, index, sample_index, 5u),
                          random(params.seed, index, sample_index, 6u));
            uint texel;
            vec3 wi = equirect_sample(u, texel);
            float q = equirect_texel_density(texel);
            if (!(q > 0.0)) continue;
            counts += vec2(beta, dot(n, wi) > 0.0 && dot(side, wi) > 0.0 ? beta : 0.0);
            vec3 s = integrand(m, n, side, wo, wi);
            if (!(max(max(s.r, s.g), s.b) > 0.0)) continue;
            float denominator = 0.5 * q + 0.5 * bsdf_pdf(m, n, wo, wi);
            if (visible(origin, wi)) sum += beta * s / denominator;
        }
        for (uint i = 0u; i < whole; ++i) {
            float beta = min(1.0, half_count - float(i));
            uint sample_index = params.frame * whole + i;
            vec3 u = vec3(random(params.seed, index, sample_index, 0u),
                          random(params.seed, index, sample_index, 1u),
                          random(params.seed, index, sample_index, 2u));
            vec3 wi;
            if (!bsdf_sample(m, n, wo, u, wi)) continue;
            float pdf_b = bsdf_pdf(m, n, wo, wi);
            if (!(pdf_b > 0.0)) continue;
            vec3 s = integrand(m, n, side, wo, wi);
            if (!(max(max(s.r, s.g), s.b) > 0.0)) continue;
            float denominator = 0.5 * equirect_density(wi) + 0.5 * pdf_b;
            if (visible(origin, wi)) sum += beta * s / denominator;
        }
        env_sample_counts[index] += counts;
        accumulate_radiance(index, sum / ns);
        return;
    }

    float mu[6];
    face_shares(n, mu);
    // With a = light_share: M_f = mu_f a N_s light samples from face f, the last one weighted
    // by frac(M_f) (or, with integer counts, round(M_f) samples of weight 1: the thesis's
    // comparison, Fig. 3.9), and N_B = (1 - a) N_s BRDF samples, every sample weighted by the
    // balance heuristic over the counts actually taken (Veach's multi-sample form):
    //   s / (M_face(w) pdf_L(w | face(w)) + N_B pdf_B(w)),
    // which is Eq. 3.7 for a = 1/2 and fractional counts, and Eq. 3.5 for a = 1.
    float a = params.light_share;
    float brdf_count = (1.0 - a) * ns;
    float taken[6];
    for (uint f = 0u; f < 6u; ++f) {
        float count = mu[f] * a * ns;
        taken[f] = params.integer_counts != 0u ? round(count) : count;
    }
    for (uint f = 0u; f < 6u; ++f) {
        float count = taken[f];
        uint n_f = min(uint(ceil(count)), params.per_face);
        for (uint i = 0u; i < n_f; ++i) {
            float beta = min(1.0, count - float(i));
            vec4 ls = env_samples[f * params.per_face + i];
            if (!(ls.w > 0.0)) continue;
            vec3 wi = ls.xyz;
            counts += vec2(beta, dot(n, wi) > 0.0 && dot(side, wi) > 0.0 ? beta : 0.0);
            vec3 s = integrand(m, n, side, wo, wi);
            if (!(max(max(s.r, s.g), s.b) > 0.0)) continue;
            float denominator = count * ls.w + brdf_count * bsdf_pdf(m, n, wo, wi);
            if (visible(origin, wi)) sum += beta * s / denominator;
        }
    }
    // BRDF samples: N_B, the last one weighted by its fraction.
    whole = uint(ceil(brdf_count));
    for (uint i = 0u; i < whole; ++i) {
        float beta = min(1.0, brdf_count - float(i));
        uint sample_index = params.frame * whole + i;
        vec3 u = vec3(random(params.seed, index, sample_index, 0u),
                      random(params.seed, index, sample_index, 1u),
                      random(params.seed, index, sample_index, 2u));
        vec3 wi;
        if (!bsdf_sample(m, n, wo, u, wi)) continue;
        float pdf_b = bsdf_pdf(m, n, wo, wi);
        if (!(pdf_b > 0.0)) continue;
        vec3 s = integrand(m, n, side, wo, wi);
        if (!(max(max(s.r, s.g), s.b) > 0.0)) continue;
        uint f;
        float pdf_l = cube_face_pdf(wi, r, f);
        float denominator = taken[f] * pdf_l + brdf_count * pdf_b;
        if (visible(origin, wi)) sum += beta * s / denominator;
    }
    env_sample_counts[index] += counts;
    accumulate_radiance(index, sum);
}
