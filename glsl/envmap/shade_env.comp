#version 450
// The `env` method's shading (Lu 14 Section 3.3, Alg. 2, and Chapter 5), direct light of the
// environment map with visibility (a shadow ray per sample), at each G-buffer point p with
// shading normal n. Cube-map light samples come from the frame's pre-generated per-face
// samples (EnvSamples): each face's sequence is cut into `windows` windows of per_face samples
// and each pixel reads its own window (a hash of pixel, frame and set), so the pixels' errors
// do not all move together; windows 1 is Lu's one set shared by every pixel. The radiance is always the scene's own map
// (envmap.glsl), the tables only drive the pdf. Strategies:
//   dynamic (0): mu_f(n) = F_f(n) I_f / sum_g F_g(n) I_g (Eq. 3.4), F_f(n) the sum of
//     <n, c>+ over the face's normalized corners; N_s / 2 light samples split over the faces
//     as fractional counts M_f = mu_f N_s / 2 with the beta weights (Eq. 3.5-3.6), and N_s / 2
//     BRDF samples, combined by the balance heuristic (Eq. 3.7):
//       g = s / (mu_f pdf_L(w | f) / 2 + pdf_B(w) / 2),
//       h = s / (mu_face(w) pdf_L(w | face(w)) / 2 + pdf_B(w) / 2),
//     L = (sum of beta g + sum of beta h) / N_s, unbiased whatever the split (N_L = N_B).
//     With light_share 1 (light only): all N_s from the faces, g = s / (mu_f pdf_L) (Eq. 3.5).
//   uniform-faces (1): the same with mu_f = 1/6 (the thesis's comparison).
//   alpha (6): dynamic's two samplers split per pixel by Lu's Chapter 5: M = alpha_samples
//     samples half and half (as dynamic) estimate the two integrals of Eq. 5.5 from the
//     luminance of the integrand with visibility, alpha = (2 + I_1 / I_2) / 4 (Eq. 5.4, alpha
//     the BRDF share N_B / N of Eq. 5.3) clamped to [0.025, 0.975]; then N = N_s - M samples,
//     alpha N from the BRDF and (1 - alpha) N from the faces (a second, independently
//     scrambled sample set, so alpha does not depend on the samples it weighs), balance
//     heuristic; the two estimates combined by Eq. 5.6, L = (M L_M + N L_N) / (M + N). The
//     frame's alpha is added to EnvAlpha (the alpha map).
//   latlong (4): N_s / 2 light samples per pixel from one table over the whole
//     equirectangular map (luminance times solid angle: the pbrt/Mitsuba sampler,
//     equirect_table.glsl), random per pixel, and N_s / 2 BRDF samples, balance heuristic.
//   hierarchical (5): the same with the luminance pyramid descended 2x2 per level
//     (env_pyramid.glsl: Falcor's and Mitsuba 3's sampler).
//   brdf (2): N_s BRDF samples, s / pdf_B.
//   cosine (3): N_s cosine-weighted directions about n, s / (cos / pi).
// BRDF, cosine, latlong and hierarchical samples are random per pixel (seed, pixel, sample).
//
// A frame's samples are split over dispatches: each pixel's samples are numbered in a fixed
// order (the light samples face by face, then the BRDF samples; alpha numbers each step's on
// its own), and a dispatch takes those in [item_begin, item_end) and adds their share of the
// estimate. lavapipe stops an invocation's loops silently after 65535 iterations in all
// (docs/DESIGN.md "The loop budget"), and each sample's shadow ray is a traversal loop: unsplit, 16384 samples
// per pixel on glossy-env came out 10% dark and 65536 up to 80%. Every sample keeps its
// random numbers, so the split changes only the order of the sums.

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
#include "env_pyramid.glsl"

// Per sample set s, face f, window w and sample k: slot ((s * 6 + f) * windows + w) * per_face + k.
layout(set = 0, binding = 24, std430) readonly buffer EnvSamples { vec4 env_samples[]; };
// Per pixel, summed over frames: x the light samples used (their beta weights), y those that
// are effective (above the surface: not cancelled by the cosine; Lu Fig. 3.6).
layout(set = 0, binding = 25, std430) buffer EnvSampleCounts { vec2 env_sample_counts[]; };
// alpha: per pixel, x the frames' alpha (the BRDF share) summed, y the frames that saw a
// surface there.
layout(set = 0, binding = 27, std430) buffer EnvAlpha { vec2 env_alpha[]; };
// alpha: per pixel, Eq. 5.5's two sums over the frame's first-step samples, summed over the
// first step's dispatches (the first one writes, the others add), read by the second step's.
layout(set = 0, binding = 28, std430) buffer EnvAlphaTerms { vec2 env_alpha_terms[]; };

layout(push_constant) uniform ShadeParams {
    uint resolution;  // R
    uint per_face;    // pre-generated samples per face and set (at least N_s / 2)
    uint strategy;
    float spp;        // N_s
    uint frame;
    uint seed;
    float light_share;  // dynamic and uniform-faces: the share of N_s taken by light samples,
                        // 1/2 (Eq. 3.7, with BRDF samples) or 1 (light only, Eq. 3.5)
    uint integer_counts;  // 1: round(M_f) samples per face instead of beta-weighted M_f
    float alpha_samples;  // alpha: M, the samples that estimate alpha
    uint shadows;         // 0: no shadow rays (every sample visible: the thesis's timings)
    uint windows;         // windows of per_face samples per face and set (1: shared by all)
    uint item_begin;      // this dispatch's samples: [item_begin, item_end) of the pixel's
    uint item_end;
    uint alpha_step;      // alpha: 1 for the samples that estimate alpha, 2 for the rest
} params;

// The indices in 0..count of a loop whose samples are numbered from `offset` in the pixel's
// order that this dispatch takes: [first_item(offset, count), end_item(offset, count)).
uint first_item(uint offset, uint count) {
    return params.item_begin > offset ? min(params.item_begin - offset, count) : 0u;
}
uint end_item(uint offset, uint count) {
    return params.item_end > offset ? min(params.item_end - offset, count) : 0u;
}

#define STRATEGY_DYNAMIC 0u
#define STRATEGY_UNIFORM_FACES 1u
#define STRATEGY_BRDF 2u
#define STRATEGY_COSINE 3u
#define STRATEGY_LATLONG 4u
#define STRATEGY_HIERARCHICAL 5u
#define STRATEGY_ALPHA 6u

// Lu 14 Section 5.4.3.
#define ALPHA_MIN 0.025
#define ALPHA_MAX 0.975

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
    return params.shadows == 0u || !trace_any(origin, wi, infinity());
}

bool nonzero(vec3 s) {
    return max(max(s.r, s.g), s.b) > 0.0;
}

// Where the shading point is, and the pixel's random-number keys.
struct Shading {
    Material m;
    vec3 n;
    vec3 side;
    vec3 wo;
    vec3 origin;
    uint pixel;
};

// BRDF sample i of at most `stride` per frame (the same stride every frame and pixel, so no
// two frames share a sample index), random dimensions from `dim`.
bool brdf_sample(Shading p, uint stride, uint i, uint dim, out vec3 wi, out float pdf) {
    uint sample_index = params.frame * stride + i;
    vec3 u = vec3(random(params.seed, p.pixel, sample_index, dim),
                  random(params.seed, p.pixel, sample_index, dim + 1u),
                  random(params.seed, p.pixel, sample_index, dim + 2u));
    pdf = 0.0;
    if (!bsdf_sample(p.m, p.n, p.wo, u, wi)) return false;
    pdf = bsdf_pdf(p.m, p.n, p.wo, wi);
    return pdf > 0.0;
}

// The light density of the cube sampler with face shares mu: mu_face(w) pdf_L(w | face(w)).
float cube_light_density(float mu[6], vec3 wi) {
    uint f;
    float pdf = cube_face_pdf(wi, params.resolution, f);
    return mu[f] * pdf;
}

// The second-order terms of Lu's Eq. 5.5 for one sample of the half-and-half mixture, its
// contribution f (the luminance of s times visibility) and its two densities, weighted by
// beta: x = f / pdf_mean, (beta x^2 dpdf / pdf_mean, beta x^2 dpdf^2 / pdf_mean^2).
vec2 alpha_terms(float beta, float f, float pdf_l, float pdf_b) {
    float mean = 0.5 * (pdf_b + pdf_l);
    float delta = 0.5 * (pdf_b - pdf_l);
    if (!(mean > 0.0) || !(f > 0.0)) return vec2(0.0);
    float x = f / mean;
    float r = delta / mean;
    return beta * x * x * vec2(r, r * r);
}

// The cube sampler with face shares mu and `brdf_count` BRDF samples (random dimensions from
// `dim`): taken[f] light samples from face f of sample set `set` (the last one weighted by its
// fraction), every sample weighted by the balance heuristic over the counts taken (Veach's
// multi-sample form), s / (M_face(w) pdf_L(w | face(w)) + N_B pdf_B(w)). Returns the
// estimate; adds the light samples used and effective to `counts` and, for alpha's first
// step, Eq. 5.5's sums to `terms`. Only this dispatch's samples: the light samples face by
// face, then the BRDF samples.
vec3 estimate_cube(Shading p, float mu[6], float taken[6], float brdf_count, uint set,
                   uint dim, bool moments, inout vec2 counts, inout vec2 terms) {
    vec3 sum = vec3(0.0);
    float light_count = 0.0;
    for (uint f = 0u; f < 6u; ++f) light_count += taken[f];
    uint window = params.windows > 1u
        ? hash4(params.seed, p.pixel, params.frame, 0x77696e64u + set) % params.windows
        : 0u;
    uint offset = 0u;
    for (uint f = 0u; f < 6u; ++f) {
        float count = taken[f];
        uint n_f = min(uint(ceil(count)), params.per_face);
        uint end = end_item(offset, n_f);
        for (uint i = first_item(offset, n_f); i < end; ++i) {
            float beta = min(1.0, count - float(i));
            vec4 ls = env_samples[((set * 6u + f) * params.windows + window) * params.per_face + i];
            if (!(ls.w > 0.0)) continue;
            vec3 wi = ls.xyz;
            counts += vec2(beta, dot(p.n, wi) > 0.0 && dot(p.side, wi) > 0.0 ? beta : 0.0);
            vec3 s = integrand(p.m, p.n, p.side, p.wo, wi);
            if (!nonzero(s) || !visible(p.origin, wi)) continue;
            float pdf_b = bsdf_pdf(p.m, p.n, p.wo, wi);
            sum += beta * s / (count * ls.w + brdf_count * pdf_b);
            if (moments && light_count > 0.0) {
                terms += alpha_terms(beta, luminance(s), count / light_count * ls.w, pdf_b);
            }
        }
        offset += n_f;
    }
    uint whole = uint(ceil(brdf_count));
    uint stride = uint(ceil(params.spp));
    uint end = end_item(offset, whole);
    for (uint i = first_item(offset, whole); i < end; ++i) {
        float beta = min(1.0, brdf_count - float(i));
        vec3 wi;
        float pdf_b;
        if (!brdf_sample(p, stride, i, dim, wi, pdf_b)) continue;
        vec3 s = integrand(p.m, p.n, p.side, p.wo, wi);
        if (!nonzero(s) || !visible(p.origin, wi)) continue;
        uint f;
        float pdf_l = cube_face_pdf(wi, params.resolution, f);
        sum += beta * s / (taken[f] * pdf_l + brdf_count * pdf_b);
        if (moments) {
            terms += alpha_terms(beta, luminance(s), mu[f] * pdf_l, pdf_b);
        }
    }
    return sum;
}

// latlong and hierarchical: a direction from the global table, with its density.
bool global_sample(vec4 u, out vec3 wi, out float pdf) {
    wi = vec3(0.0, 1.0, 0.0);
    pdf = 0.0;
    if (params.strategy == STRATEGY_HIERARCHICAL) return pyramid_sample(u, wi, pdf);
    if (equirect_table_empty()) return false;
    uint texel;
    wi = equirect_sample(u, texel);
    pdf = equirect_texel_density(texel);
    return pdf > 0.0;
}

float global_density(vec3 wi) {
    return params.strategy == STRATEGY_HIERARCHICAL ? pyramid_density(wi) : equirect_density(wi);
}

void main() {
    uvec2 pixel = gl_GlobalInvocationID.xy;
    if (pixel.x >= scene.size.x || pixel.y >= scene.size.y) return;
    uint index = pixel.y * scene.size.x + pixel.x;
    GBufferTexel g = gbuffer[index];
    Shading p;
    if (!gbuffer_surface(g, p.wo, p.side, p.n)) return;
    p.m = gbuffer_material(g);
    p.origin = offset_origin(g.position.xyz, p.side);
    p.pixel = index;
    float ns = params.spp;
    vec3 sum = vec3(0.0);

    if (params.strategy == STRATEGY_BRDF || params.strategy == STRATEGY_COSINE) {
        uint count = uint(ns);
        uint end = end_item(0u, count);
        for (uint k = first_item(0u, count); k < end; ++k) {
            vec3 wi;
            float pdf;
            if (params.strategy == STRATEGY_BRDF) {
                if (!brdf_sample(p, count, k, 0u, wi, pdf)) continue;
            } else {
                uint sample_index = params.frame * count + k;
                vec2 u = vec2(random(params.seed, index, sample_index, 0u),
                              random(params.seed, index, sample_index, 1u));
                wi = to_world(sample_cosine_hemisphere(u), p.n);
                pdf = max(dot(p.n, wi), 0.0) * INV_PI;
            }
            if (!(pdf > 0.0)) continue;
            vec3 s = integrand(p.m, p.n, p.side, p.wo, wi);
            if (nonzero(s) && visible(p.origin, wi)) sum += s / pdf;
        }
        accumulate_radiance(index, sum / max(float(count), 1.0));
        return;
    }

    vec2 counts = vec2(0.0);

    if (params.strategy == STRATEGY_LATLONG || params.strategy == STRATEGY_HIERARCHICAL) {
        float half_count = 0.5 * ns;
        uint whole = uint(ceil(half_count));
        uint end = end_item(0u, whole);
        for (uint i = first_item(0u, whole); i < end; ++i) {
            float beta = min(1.0, half_count - float(i));
            uint sample_index = params.frame * whole + i;
            vec4 u = vec4(random(params.seed, index, sample_index, 3u),
                          random(params.seed, index, sample_index, 4u),
                          random(params.seed, index, sample_index, 5u),
                          random(params.seed, index, sample_index, 6u));
            vec3 wi;
            float q;
            if (!global_sample(u, wi, q)) continue;
            counts += vec2(beta, dot(p.n, wi) > 0.0 && dot(p.side, wi) > 0.0 ? beta : 0.0);
            vec3 s = integrand(p.m, p.n, p.side, p.wo, wi);
            if (!nonzero(s)) continue;
            float denominator = 0.5 * q + 0.5 * bsdf_pdf(p.m, p.n, p.wo, wi);
            if (visible(p.origin, wi)) sum += beta * s / denominator;
        }
        end = end_item(whole, whole);
        for (uint i = first_item(whole, whole); i < end; ++i) {
            float beta = min(1.0, half_count - float(i));
            vec3 wi;
            float pdf_b;
            if (!brdf_sample(p, whole, i, 0u, wi, pdf_b)) continue;
            vec3 s = integrand(p.m, p.n, p.side, p.wo, wi);
            if (!nonzero(s)) continue;
            float denominator = 0.5 * global_density(wi) + 0.5 * pdf_b;
            if (visible(p.origin, wi)) sum += beta * s / denominator;
        }
        env_sample_counts[index] += counts;
        accumulate_radiance(index, sum / ns);
        return;
    }

    float mu[6];
    face_shares(p.n, mu);
    vec2 terms = vec2(0.0);

    if (params.strategy == STRATEGY_ALPHA) {
        float m_count = clamp(params.alpha_samples, 0.0, ns);
        float n_count = ns - m_count;
        float taken[6];
        if (params.alpha_step == 1u) {
            // Step 1: M samples half and half, which also estimate alpha.
            for (uint f = 0u; f < 6u; ++f) taken[f] = mu[f] * 0.5 * m_count;
            vec3 first =
                estimate_cube(p, mu, taken, 0.5 * m_count, 0u, 0u, true, counts, terms);
            env_alpha_terms[index] =
                params.item_begin == 0u ? terms : env_alpha_terms[index] + terms;
            env_sample_counts[index] += counts;
            // Eq. 5.6: each step's estimate is its sum (the balance heuristic's multi-sample
            // form divides by the counts already); weighted by M / (M + N) and N / (M + N).
            accumulate_radiance(index, m_count * first / ns);
            return;
        }
        terms = env_alpha_terms[index];
        float ratio = terms.x / terms.y;
        // No contribution (or an overflow) gives no evidence: the balance heuristic's half.
        float alpha = terms.y > 0.0 && !isinf(terms.y) && !isnan(ratio)
                          ? clamp(0.25 * (2.0 + ratio), ALPHA_MIN, ALPHA_MAX)
                          : 0.5;
        // Step 2: N samples split by alpha, from the second sample set and other dimensions.
        for (uint f = 0u; f < 6u; ++f) taken[f] = mu[f] * (1.0 - alpha) * n_count;
        vec3 second = estimate_cube(p, mu, taken, alpha * n_count, 1u, 8u, false, counts, terms);
        if (params.item_begin == 0u) env_alpha[index] += vec2(alpha, 1.0);
        env_sample_counts[index] += counts;
        accumulate_radiance(index, n_count * second / ns);
        return;
    }

    // With a = light_share: M_f = mu_f a N_s light samples from face f, the last one weighted
    // by frac(M_f) (or, with integer counts, round(M_f) samples of weight 1: the thesis's
    // comparison, Fig. 3.9), and N_B = (1 - a) N_s BRDF samples, every sample weighted by the
    // balance heuristic over the counts actually taken: Eq. 3.7 for a = 1/2 and fractional
    // counts, and Eq. 3.5 for a = 1.
    float a = params.light_share;
    float taken[6];
    for (uint f = 0u; f < 6u; ++f) {
        float count = mu[f] * a * ns;
        taken[f] = params.integer_counts != 0u ? round(count) : count;
    }
    sum = estimate_cube(p, mu, taken, (1.0 - a) * ns, 0u, 0u, false, counts, terms);
    env_sample_counts[index] += counts;
    accumulate_radiance(index, sum);
}
