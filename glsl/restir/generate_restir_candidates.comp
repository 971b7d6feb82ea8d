#version 450
// ReSTIR DI's initial candidates (Bitterli et al. 2020, Section 3 and Alg. 3), per pixel and
// frame: M light candidates (light_sampler: through the light BVH, the constant LIGHT_BVH, or
// by power; the environment by its share of the light table in both) and B BSDF candidates (a
// BSDF-sampled ray's emissive hit or, escaping, the environment), combined by multiple
// importance resampling (Talbot et al. 2005): candidate y of either strategy has weight
// p^(y) / (M p_light(y) + B p_bsdf(y)), the balance heuristic over both, so W = (sum of the
// weights) / p^(y) needs no 1 / M. The chosen sample's shadow ray zeroes W where it is hidden
// (visibility reuse; restir.glsl's invariant).
//
// A visibility-aware target (setting candidate_shadow_rays, T): the candidates are dealt into T
// interleaved streams (light candidate j and BSDF candidate k to streams j mod T and k mod T),
// each resampled as above with the weights of the whole pool; each stream's pick gets a shadow
// ray, and the visible picks are resampled by their streams' weight sums. That is resampling
// by p^ V over T samples: sum_t f(y_t) W_t is unbiased (the pool's balance weights sum to one
// over all candidates, each stream's W_t is zero where its pick is hidden), and choosing t with
// probability proportional to p^(y_t) W_t = (stream t's weight sum) with W = (sum over the
// visible streams) / p^(y) keeps that mean. T = 1 is the single shadow ray above, bit for bit.
//
// Loop budget (docs/DESIGN.md "The loop budget"): at most 512 light candidates (the setting's
// range), each a descent of at most 64 levels (tens on real scenes: 14 levels for 4288
// lights) plus the environment texel's binary search (log2 of the map's texels) or the power
// table's (log2 of the lights), so at most about 512 x (1 + 64 + 24) = 45000 iterations before
// the rays, and at most 16 BSDF candidates, each one traversal, plus one shadow ray.
// Then one shadow ray for each of at most 8 streams (candidate_shadow_rays).
// tests/setting_maxima.rs runs 512 candidates on many-lights-sky, and 8 streams with 512 light
// and 16 BSDF candidates.
//
// Random numbers per (pass seed, pixel, frame): light candidate j hashes dimension 16 + j once and
// draws its selection, texel, position (2) and resampling numbers from that hash, PCG-hashed
// with 0..4 (one hash4 a candidate instead of five); BSDF candidate j uses dimensions
// 16 + 4096 + 8 j .. +3 (direction 3, resampling); stream t's final resampling dimension
// 16 + 4096 + 128 + t.

#extension GL_GOOGLE_include_directive : require

layout(local_size_x = 8, local_size_y = 8, local_size_z = 1) in;

#include "bvh.glsl"
#include "scene.glsl"
#include "sampling.glsl"
#include "bsdf.glsl"
#include "lights.glsl"
#include "light_bvh.glsl"
#include "gbuffer.glsl"
#include "restir.glsl"
#include "radiance.glsl"

layout(push_constant) uniform CandidateParams {
    uint frame;
    uint seed;
    uint light_candidates;
    uint bsdf_candidates;
    uint streams;
} params;

// How light candidates are drawn (src/methods/restir/kernels.rs specializes it): through
// the light BVH (true) or by power (false).
layout(constant_id = 4) const bool LIGHT_BVH = true;

const uint LIGHT_DIMENSIONS = 16u;
// After the most light candidates (src/methods/restir/mod.rs's MAX_CANDIDATES)...
const uint BSDF_DIMENSIONS = 16u + 8u * 512u;
// ...and the most BSDF candidates (MAX_BSDF_CANDIDATES); a unit test of mod.rs holds these
// to the Rust constants.
const uint STREAM_DIMENSIONS = BSDF_DIMENSIONS + 8u * 16u;
// The most streams (MAX_CANDIDATE_SHADOW_RAYS).
const uint MAX_STREAMS = 8u;

void main() {
    uvec2 pixel = gl_GlobalInvocationID.xy;
    if (pixel.x >= scene.size.x || pixel.y >= scene.size.y) return;
    uint index = pixel.y * scene.size.x + pixel.x;
    float m_light = float(params.light_candidates);
    float m_bsdf = float(params.bsdf_candidates);
    RestirPoint s = restir_point_from_gbuffer(index);
    if (!s.valid) {
        reservoirs[index] = empty_reservoir(0.0);
        return;
    }
    Material m = s.m;
    uint seed = params.seed;
    uint frame = params.frame;

    // Each stream's weight sum and pick (the pick's target in its measure, as stored).
    float weight_sum[MAX_STREAMS];
    uint chosen_entry[MAX_STREAMS];
    vec3 chosen_y[MAX_STREAMS];
    float chosen_target[MAX_STREAMS];
    uint streams = min(max(params.streams, 1u), MAX_STREAMS);
    for (uint t = 0u; t < MAX_STREAMS; ++t) {
        weight_sum[t] = 0.0;
        chosen_entry[t] = NO_LIGHT;
        chosen_y[t] = vec3(0.0);
        chosen_target[t] = 0.0;
    }

    // A do-while (bvh.glsl's triangle loop says why); light_candidates is at least 1. The
    // target is evaluated from the light sample itself (solid angle; the candidate weight is a
    // ratio of densities, the same in any measure) and turned into the light's measure only
    // for the chosen sample: the light's data is loaded once.
    uint j = 0u;
    do {
        uint h = hash4(seed, index, frame, LIGHT_DIMENSIONS + j);
        uint r_select = pcg_hash(h) >> 1u;
        uint r_texel = pcg_hash(h ^ 0x1u) >> 1u;
        vec2 u = vec2(unit_float(pcg_hash(h ^ 0x2u)), unit_float(pcg_hash(h ^ 0x3u)));
        LightSample ls;
        bool sampled = LIGHT_BVH ? sample_light_bvh(s.p, s.n, r_select, 1.0, r_texel, u, ls)
                                 : sample_light(s.p, r_select, r_texel, u, ls);
        float cos_i = dot(ls.direction, s.n);
        if (sampled && cos_i > 0.0 && dot(ls.direction, s.side) > 0.0) {
            float target = luminance(bsdf_eval(m, s.n, s.wo, ls.direction) * cos_i * ls.radiance);
            if (target > 0.0) {
                float p_bsdf = ls.delta ? 0.0 : bsdf_pdf(m, s.n, s.wo, ls.direction);
                float w = target / (m_light * ls.pdf + m_bsdf * p_bsdf);
                uint t = j % streams;
                if (reservoir_take(weight_sum[t], w, unit_float(pcg_hash(h ^ 0x4u)))) {
                    chosen_entry[t] = ls.entry;
                    chosen_y[t] = isinf(ls.distance) ? ls.direction
                                                     : s.p + ls.direction * ls.distance;
                    chosen_target[t] = target * ls.to_area;
                }
            }
        }
        ++j;
    } while (j < params.light_candidates);

    vec3 origin = offset_origin(s.p, s.side);
    for (uint k = 0u; k < params.bsdf_candidates; ++k) {
        uint dim = BSDF_DIMENSIONS + 8u * k;
        vec3 u = vec3(random(seed, index, frame, dim), random(seed, index, frame, dim + 1u),
                      random(seed, index, frame, dim + 2u));
        vec3 wi;
        if (!bsdf_sample(m, s.n, s.wo, u, wi)) continue;
        float p_bsdf = bsdf_pdf(m, s.n, s.wo, wi);
        if (!(p_bsdf > 0.0) || dot(wi, s.side) <= 0.0) continue;
        RayHit hit;
        bool found = trace_closest(origin, wi, infinity(), hit);
        uint entry = NO_LIGHT;
        vec3 y = wi;
        float p_light = 0.0;
        if (found) {
            ShadingTriangle st = shading_triangles[hit.triangle];
            Material hm = materials[floatBitsToUint(st.n0.w)];
            if (hm.ke.w > 0.0 && dot(wi, st.geometric_normal.xyz) < 0.0) {
                entry = floatBitsToUint(st.geometric_normal.w);
                y = origin + hit.t * wi;
                float probability = LIGHT_BVH ? light_bvh_triangle_probability(st, s.p, s.n)
                                              : st.n1.w;
                p_light = light_pdf_triangle_chosen(st, wi, hit.t, probability);
            }
        } else if (SCENE_HAS_ENVIRONMENT && scene.env.x > 0.0) {
            entry = scene.size.z - 1u;
            p_light = light_pdf_environment(wi);
        }
        if (entry >= scene.size.z) continue;
        vec3 w_dir;
        float dist, to_area;
        float target = luminance(restir_contribution(s, entry, y, w_dir, dist, to_area));
        if (!(target > 0.0)) continue;
        float w = target / ((m_light * p_light + m_bsdf * p_bsdf) * to_area);
        // Dealt on after the light candidates, so that the streams' sizes differ by at most one.
        uint t = (params.light_candidates + k) % streams;
        if (reservoir_take(weight_sum[t], w, random(seed, index, frame, dim + 3u))) {
            chosen_entry[t] = entry;
            chosen_y[t] = y;
            chosen_target[t] = target;
        }
    }

    Reservoir r = empty_reservoir(m_light + m_bsdf);
    // Weights past f32's range (a light too bright for its distance) drop the reservoir; it is
    // counted as a non-finite estimate so that the render's record warns.
    bool finite = true;
    for (uint t = 0u; t < streams; ++t) {
        finite = finite && !(isnan(weight_sum[t]) || isinf(weight_sum[t]));
    }
    if (!finite) {
        count_nonfinite_estimate();
        reservoirs[index] = r;
        return;
    }
    // The visible picks resampled by their streams' weight sums (the header). Where none is
    // visible the reservoir keeps the first non-empty stream's pick with W = 0 (T = 1's hidden
    // sample).
    float visible_sum = 0.0;
    uint kept = NO_LIGHT;
    for (uint t = 0u; t < streams; ++t) {
        if (chosen_entry[t] == NO_LIGHT || !(weight_sum[t] > 0.0)) continue;
        if (kept == NO_LIGHT) kept = t;
        if (restir_visible(s, chosen_entry[t], chosen_y[t])
            && reservoir_take(visible_sum, weight_sum[t],
                              random(seed, index, frame, STREAM_DIMENSIONS + t))) {
            kept = t;
        }
    }
    // Finite streams can still sum past f32's range (T > 1): dropped and counted as above.
    if (isinf(visible_sum)) {
        count_nonfinite_estimate();
        reservoirs[index] = r;
        return;
    }
    if (kept != NO_LIGHT) {
        r.sample_point = vec4(chosen_y[kept], uintBitsToFloat(chosen_entry[kept]));
        r.weights.z = chosen_target[kept];
        r.weights.x = visible_sum > 0.0 ? visible_sum / chosen_target[kept] : 0.0;
    }
    reservoirs[index] = r;
}
