#version 450
// ReSTIR DI's temporal reuse (Bitterli et al. 2020, Section 4 and Alg. 5): this frame's
// candidate reservoir (c, at this frame's surface s) combined with the same pixel's final
// reservoir of the previous frame (p, at its surface q: the G-buffer is re-jittered every
// frame, so q is kept in PreviousSurfaces; the view is static), p's M capped at `cap` times c's.
// The result keeps restir.glsl's invariant. Combinations:
// - mis (the default): the balance heuristic over the two domains, p^ V standing for each one's
//   density (GRIS, Lin et al. 2022, with confidence weights M): reservoir i's sample y_i enters
//   with weight m_i(y_i) p^_s(y_i) V_s(y_i) W_i, m_i(y) = M_i p^_i V_i(y) / sum_j M_j p^_j V_j(y),
//   and W = (sum of weights) / p^_s(y). Two shadow rays: c's sample from q, p's from s. The
//   weights are bounded by the targets' ratio, where 1 / Z's are not.
// - one-over-z: weights p^_s(y_i) W_i M_i, W = (sum of weights) / (Z p^_s(y)), Z the M of the
//   reservoirs whose surface could have produced y (p^ > 0 there and y visible from it: Alg. 6's
//   1 / Z with visibility), one shadow ray for the one not known and one for y from s.
// - biased: as one-over-z with Z the sum of both M (Alg. 5).
// q is lit as the previous frame was (restir.glsl's "Frames"): p's stored target and c's target
// at q take the previous frame's environment map, s's this frame's.

#extension GL_GOOGLE_include_directive : require

layout(local_size_x = 8, local_size_y = 8, local_size_z = 1) in;

#include "bvh.glsl"
#include "scene.glsl"
#include "sampling.glsl"
#include "bsdf.glsl"
#include "lights.glsl"
#include "gbuffer.glsl"
#define RESTIR_PREVIOUS_FRAME
#include "restir.glsl"
#include "radiance.glsl"

layout(push_constant) uniform TemporalParams {
    uint frame;
    uint seed;
    float cap;        // the previous reservoir's M at most cap times this one's
    uint combination; // COMBINATION_* (restir.glsl)
    uint previous_env_base; // the previous frame's map in PreviousEnvTexels, in texels
} params;

// Dimension of the selection's random number (the pass has its own seed: kernels.rs).
const uint TEMPORAL_DIMENSION = 1u;

void main() {
    uvec2 pixel = gl_GlobalInvocationID.xy;
    if (pixel.x >= scene.size.x || pixel.y >= scene.size.y) return;
    uint index = pixel.y * scene.size.x + pixel.x;
    restir_previous_env_base = params.previous_env_base;
    RestirPoint s = restir_point_from_gbuffer(index);
    Reservoir current = reservoirs[index];
    Reservoir previous = final_reservoirs[index];
    RestirPoint q = restir_point_from_surface(previous_surfaces[index]);
    if (!s.valid) return;

    float m_current = current.weights.y;
    float m_previous = q.valid ? min(previous.weights.y, params.cap * m_current) : 0.0;
    uint e_current = floatBitsToUint(current.sample_point.w);
    uint e_previous = floatBitsToUint(previous.sample_point.w);
    vec3 y_current = current.sample_point.xyz;
    vec3 y_previous = previous.sample_point.xyz;
    float u = random(params.seed, index, params.frame, TEMPORAL_DIMENSION);
    Reservoir r = empty_reservoir(m_current + m_previous);

    if (params.combination == COMBINATION_MIS) {
        // p^ V of each sample at its own surface: its stored target where W > 0 (the invariant).
        float own_current = current.weights.x > 0.0 ? current.weights.z : 0.0;
        float own_previous = m_previous > 0.0 && previous.weights.x > 0.0
            ? previous.weights.z : 0.0;
        // ... and at the other surface.
        float current_at_q = own_current > 0.0 && m_previous > 0.0
            ? restir_visible_target(q, e_current, y_current) : 0.0;
        float previous_at_s = own_previous > 0.0
            ? restir_visible_target(s, e_previous, y_previous) : 0.0;
        float weight_sum = 0.0;
        reservoir_take(weight_sum,
                       balance_share(m_current * own_current, m_previous * current_at_q)
                           * own_current * current.weights.x,
                       0.0);
        bool from_previous = reservoir_take(
            weight_sum,
            balance_share(m_previous * own_previous, m_current * previous_at_s) * previous_at_s
                * previous.weights.x,
            u);
        float target = from_previous ? previous_at_s : own_current;
        // Weights past f32's range drop the reservoir, counted (as the other passes do).
        bool finite = !(isnan(weight_sum) || isinf(weight_sum));
        if (!finite) count_nonfinite_estimate();
        float w = finite && target > 0.0 ? weight_sum / target : 0.0;
        // W past f32's range (a tiny target) drops the reservoir too, counted.
        if (finite && (isinf(w) || isnan(w))) {
            count_nonfinite_estimate();
            w = 0.0;
        }
        if (weight_sum > 0.0 && w > 0.0) {
            r.sample_point = from_previous ? previous.sample_point : current.sample_point;
            r.weights.z = target;
            r.weights.x = w;
        }
        reservoirs[index] = r;
        return;
    }

    float weight_sum = 0.0;
    float w_current = current.weights.z * current.weights.x * m_current;
    reservoir_take(weight_sum, w_current, 0.0);
    float target_previous = 0.0;
    if (m_previous > 0.0 && previous.weights.x > 0.0) {
        target_previous = restir_target(s, e_previous, y_previous);
    }
    float w_previous = target_previous * previous.weights.x * m_previous;
    bool from_previous = reservoir_take(weight_sum, w_previous, u);

    bool finite = !(isnan(weight_sum) || isinf(weight_sum));
    if (!finite) count_nonfinite_estimate();
    if (weight_sum > 0.0 && finite) {
        uint entry = from_previous ? e_previous : e_current;
        vec3 y = from_previous ? y_previous : y_current;
        float target = from_previous ? target_previous : current.weights.z;
        // Visibility from this frame's surface: known for its own sample (W > 0).
        bool visible = from_previous ? restir_visible(s, entry, y) : true;
        float z = m_current + m_previous;
        if (params.combination == COMBINATION_ONE_OVER_Z) {
            // Could the previous surface have produced y? Known for its own sample.
            bool previous_covers = from_previous;
            if (!from_previous && m_previous > 0.0 && restir_target(q, entry, y) > 0.0) {
                previous_covers = restir_visible(q, entry, y);
            }
            z = (visible ? m_current : 0.0) + (previous_covers ? m_previous : 0.0);
        }
        r.sample_point = vec4(y, uintBitsToFloat(entry));
        r.weights.z = target;
        // Z p^ past f32's range (or W past it) drops the reservoir, counted, as in the spatial
        // pass.
        float w = 0.0;
        if (visible && z > 0.0) {
            float denominator = z * target;
            w = weight_sum / denominator;
            if (isinf(denominator) || isinf(w) || isnan(w)) {
                count_nonfinite_estimate();
                w = 0.0;
            }
        }
        r.weights.x = w;
    }
    reservoirs[index] = r;
}
