#version 450
// ReSTIR DI's temporal reuse (Bitterli et al. 2020, Section 4 and Alg. 5): this frame's
// candidate reservoir combined with the same pixel's final reservoir of the previous frame
// (the view is static; the G-buffer is re-jittered, so the previous frame's surface is kept
// in PreviousSurfaces), its M capped at `cap` times this frame's. Each reservoir enters with
// weight p^(y) W M, p^ at this frame's surface. Unbiased (the default): W = (sum of weights) /
// (Z p^(y)), Z the M of the reservoirs whose surface could have produced y (p^ > 0 there and y
// visible from it: Alg. 6's 1 / Z with visibility), one shadow ray for the one not known.
// Biased: Z is the sum of both M (Alg. 5). The result keeps restir.glsl's invariant.

#extension GL_GOOGLE_include_directive : require

layout(local_size_x = 8, local_size_y = 8, local_size_z = 1) in;

#include "bvh.glsl"
#include "scene.glsl"
#include "sampling.glsl"
#include "bsdf.glsl"
#include "lights.glsl"
#include "gbuffer.glsl"
#include "restir.glsl"

layout(push_constant) uniform TemporalParams {
    uint frame;
    uint seed;
    float cap;       // the previous reservoir's M at most cap times this one's
    uint unbiased;   // 1: 1 / Z with visibility; 0: 1 / (sum of M)
} params;

// Dimension of the selection's random number (the pass has its own seed: kernels.rs).
const uint TEMPORAL_DIMENSION = 1u;

void main() {
    uvec2 pixel = gl_GlobalInvocationID.xy;
    if (pixel.x >= scene.size.x || pixel.y >= scene.size.y) return;
    uint index = pixel.y * scene.size.x + pixel.x;
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

    float weight_sum = 0.0;
    float w_current = current.weights.z * current.weights.x * m_current;
    reservoir_take(weight_sum, w_current, 0.0);
    float target_previous = 0.0;
    if (m_previous > 0.0 && previous.weights.x > 0.0) {
        target_previous = restir_target(s, e_previous, y_previous);
    }
    float w_previous = target_previous * previous.weights.x * m_previous;
    bool from_previous = reservoir_take(weight_sum, w_previous,
                                        random(params.seed, index, params.frame, TEMPORAL_DIMENSION));

    Reservoir r = empty_reservoir(m_current + m_previous);
    if (weight_sum > 0.0 && !isinf(weight_sum)) {
        uint entry = from_previous ? e_previous : e_current;
        vec3 y = from_previous ? y_previous : y_current;
        float target = from_previous ? target_previous : current.weights.z;
        // Visibility from this frame's surface: known for its own sample (W > 0).
        bool visible = from_previous ? restir_visible(s, entry, y) : true;
        float z = m_current + m_previous;
        if (params.unbiased != 0u) {
            // Could the previous surface have produced y? Known for its own sample.
            bool previous_covers = from_previous;
            if (!from_previous && m_previous > 0.0 && restir_target(q, entry, y) > 0.0) {
                previous_covers = restir_visible(q, entry, y);
            }
            z = (visible ? m_current : 0.0) + (previous_covers ? m_previous : 0.0);
        }
        r.sample_point = vec4(y, uintBitsToFloat(entry));
        r.weights.z = target;
        r.weights.x = visible && z > 0.0 ? weight_sum / (z * target) : 0.0;
    }
    reservoirs[index] = r;
}
