#version 450
// ReSTIR DI's spatial reuse (Bitterli et al. 2020, Section 4, Alg. 4 and 6): each pixel's
// reservoir (the canonical one, c) combined with those of k random neighbours within R pixels
// (uniform over the disk), a neighbour rejected where its surface differs (normals more than
// about 25 degrees apart, camera distances more than 10% apart: the paper's heuristics) or the
// camera missed. The result is the frame's final reservoir, stored with this frame's surface
// for the next frame's temporal pass; it keeps restir.glsl's invariant. Combinations:
// - mis (the default): pairwise MIS with confidence weights (Bitterli's thesis, 2022, Section
//   9.1; GRIS, Lin et al. 2022; RTXDI's pairwise mode), p^ V standing for each domain's
//   density. With n neighbours taken, M_sum the sum of every M, and pair i between neighbour i
//   and c (c holding M_c / n in each pair):
//     m_i(y) = (M_i + M_c / n) / M_sum * M_i p_i(y) / (M_i p_i(y) + M_c / n p_c(y)),
//     m_c(y) = sum_i (M_i + M_c / n) / M_sum * (M_c / n) p_c(y) / (M_i p_i(y) + M_c / n p_c(y)),
//   p_j = p^_j V_j. They sum to 1 wherever p_c > 0, which is where the pixel's integrand is,
//   so the estimate is unbiased; a weight is bounded by the targets' ratio. Reservoir j enters
//   with m_j(y_j) p_c(y_j) W_j, and W = (sum of weights) / p^_c(y). 2n shadow rays: each
//   neighbour's sample from c, c's sample from each neighbour.
// - one-over-z: weights p^_c(y_j) W_j M_j; 1 / Z, Z the M of the reservoirs whose surface could
//   have produced y (p^ > 0 there and y visible from it: a shadow ray from each but the one
//   that produced y, and one for y from c).
// - biased: as one-over-z with Z = the sum of every M taken.
//
// Loop budget: at most 16 neighbours (the setting's range): 2k shadow rays in mis, k + 1 in
// one-over-z, one in biased.

#extension GL_GOOGLE_include_directive : require

layout(local_size_x = 8, local_size_y = 8, local_size_z = 1) in;

#include "bvh.glsl"
#include "scene.glsl"
#include "sampling.glsl"
#include "bsdf.glsl"
#include "lights.glsl"
#include "gbuffer.glsl"
#include "restir.glsl"
#include "radiance.glsl"

layout(push_constant) uniform SpatialParams {
    uint frame;
    uint seed;
    uint neighbours;  // k, at most MAX_NEIGHBOURS
    float radius;     // R, pixels
    uint combination; // COMBINATION_* (restir.glsl)
    float normal_cos; // a neighbour's normal at least this close (cosine) ...
    float depth_tolerance;  // ... and its camera distance within this fraction
    uint _pad;
} params;

const uint MAX_NEIGHBOURS = 16u;
// Random dimensions: 1 for the canonical reservoir's selection under mis, 2 + 3 j .. 4 + 3 j
// for neighbour j (position, selection); the pass has its own seed (kernels.rs).
const uint CANONICAL_DIMENSION = 1u;
const uint SPATIAL_DIMENSION = 2u;

float camera_distance(vec3 p) {
    return length(p - scene.camera_position.xyz);
}

void main() {
    uvec2 pixel = gl_GlobalInvocationID.xy;
    if (pixel.x >= scene.size.x || pixel.y >= scene.size.y) return;
    uint index = pixel.y * scene.size.x + pixel.x;
    RestirPoint s = restir_point_from_gbuffer(index);
    previous_surfaces[index] = restir_surface(s);
    Reservoir own = reservoirs[index];
    if (!s.valid) {
        final_reservoirs[index] = empty_reservoir(0.0);
        return;
    }
    float depth = camera_distance(s.p);

    // The reservoirs taken: index 0 this pixel's, then the neighbours' (and their selection's
    // random dimension).
    uint taken[MAX_NEIGHBOURS + 1u];
    uint taken_dimension[MAX_NEIGHBOURS + 1u];
    taken[0] = index;
    uint count = 1u;
    float m_sum = own.weights.y;
    for (uint j = 0u; j < params.neighbours; ++j) {
        uint dim = SPATIAL_DIMENSION + 3u * j;
        float r = params.radius * sqrt(random(params.seed, index, params.frame, dim));
        float phi = 2.0 * PI * random(params.seed, index, params.frame, dim + 1u);
        ivec2 q = ivec2(pixel) + ivec2(round(r * vec2(cos(phi), sin(phi))));
        if (q.x < 0 || q.y < 0 || q.x >= int(scene.size.x) || q.y >= int(scene.size.y)) continue;
        uint qi = uint(q.y) * scene.size.x + uint(q.x);
        if (qi == index) continue;
        // The test reads the G-buffer alone (a RestirPoint would load the material too).
        GBufferTexel g = gbuffer[qi];
        vec3 g_wo, g_side, g_n;
        if (!gbuffer_surface(g, g_wo, g_side, g_n) || dot(g_n, s.n) < params.normal_cos
            || abs(camera_distance(g.position.xyz) - depth) > params.depth_tolerance * depth) {
            continue;
        }
        taken[count] = qi;
        taken_dimension[count] = dim + 2u;
        m_sum += reservoirs[qi].weights.y;
        ++count;
    }

    uint entry = floatBitsToUint(own.sample_point.w);
    vec3 y = own.sample_point.xyz;
    float weight_sum = 0.0;
    Reservoir result = empty_reservoir(m_sum);

    if (params.combination == COMBINATION_MIS) {
        float m_own = own.weights.y;
        float pair_own = m_own / float(max(count - 1u, 1u));  // c's confidence in each pair
        // p^ V of c's sample at c: its stored target where W > 0 (the invariant).
        float own_at_own = own.weights.x > 0.0 ? own.weights.z : 0.0;
        float own_mis = count == 1u ? 1.0 : 0.0;
        float target = 0.0;  // the chosen sample's p^ V at this pixel (none chosen yet)
        for (uint i = 1u; i < count; ++i) {
            Reservoir other = reservoirs[taken[i]];
            RestirPoint n = restir_point_from_gbuffer(taken[i]);
            uint other_entry = floatBitsToUint(other.sample_point.w);
            float m_other = other.weights.y;
            float pair = (m_other + pair_own) / m_sum;
            float other_at_other = other.weights.x > 0.0 ? other.weights.z : 0.0;
            float other_at_own = other_at_other > 0.0
                ? restir_visible_target(s, other_entry, other.sample_point.xyz) : 0.0;
            float own_at_other = own_at_own > 0.0 ? restir_visible_target(n, entry, y) : 0.0;
            own_mis += pair * balance_share(pair_own * own_at_own, m_other * own_at_other);
            float w = pair * balance_share(m_other * other_at_other, pair_own * other_at_own)
                * other_at_own * other.weights.x;
            if (reservoir_take(weight_sum, w,
                               random(params.seed, index, params.frame, taken_dimension[i]))) {
                result.sample_point = other.sample_point;
                target = other_at_own;
            }
        }
        bool from_own = reservoir_take(weight_sum, own_mis * own_at_own * own.weights.x,
                                       random(params.seed, index, params.frame,
                                              CANONICAL_DIMENSION));
        if (from_own) {
            result.sample_point = own.sample_point;
            target = own_at_own;
        }
        // Weights past f32's range drop the reservoir, counted (as the candidates' pass does).
        bool finite = !(isnan(weight_sum) || isinf(weight_sum));
        if (!finite) count_nonfinite_estimate();
        float w = finite && target > 0.0 ? weight_sum / target : 0.0;
        // W past f32's range (a tiny target) drops the reservoir too, counted.
        if (finite && (isinf(w) || isnan(w))) {
            count_nonfinite_estimate();
            w = 0.0;
        }
        if (weight_sum > 0.0 && w > 0.0) {
            result.weights.z = target;
            result.weights.x = w;
        } else {
            result = empty_reservoir(m_sum);
        }
        final_reservoirs[index] = result;
        return;
    }

    uint chosen = 0u;
    float target = own.weights.z;
    reservoir_take(weight_sum, own.weights.z * own.weights.x * own.weights.y, 0.0);
    for (uint i = 1u; i < count; ++i) {
        Reservoir other = reservoirs[taken[i]];
        uint other_entry = floatBitsToUint(other.sample_point.w);
        float other_target = other.weights.x > 0.0
            ? restir_target(s, other_entry, other.sample_point.xyz) : 0.0;
        float w = other_target * other.weights.x * other.weights.y;
        if (reservoir_take(weight_sum, w,
                           random(params.seed, index, params.frame, taken_dimension[i]))) {
            chosen = i;
            entry = other_entry;
            y = other.sample_point.xyz;
            target = other_target;
        }
    }

    bool finite = !(isnan(weight_sum) || isinf(weight_sum));
    if (!finite) count_nonfinite_estimate();
    if (weight_sum > 0.0 && finite) {
        bool visible = chosen == 0u ? true : restir_visible(s, entry, y);
        float z = m_sum;
        if (params.combination == COMBINATION_ONE_OVER_Z) {
            z = visible ? own.weights.y : 0.0;
            for (uint i = 1u; i < count; ++i) {
                Reservoir other = reservoirs[taken[i]];
                bool covers = i == chosen;
                if (!covers) {
                    RestirPoint n = restir_point_from_gbuffer(taken[i]);
                    covers = restir_target(n, entry, y) > 0.0 && restir_visible(n, entry, y);
                }
                if (covers) z += other.weights.y;
            }
        }
        result.sample_point = vec4(y, uintBitsToFloat(entry));
        result.weights.z = target;
        // Z p^ past f32's range (or W = weight_sum / (Z p^) past it) drops the reservoir,
        // counted as the weight sums' overflow is: a finite weight sum over an infinite Z p^
        // would otherwise give W = 0, a dark pixel without a sign.
        float w = 0.0;
        if (visible && z > 0.0) {
            float denominator = z * target;
            w = weight_sum / denominator;
            if (isinf(denominator) || isinf(w) || isnan(w)) {
                count_nonfinite_estimate();
                w = 0.0;
            }
        }
        result.weights.x = w;
    }
    final_reservoirs[index] = result;
}
