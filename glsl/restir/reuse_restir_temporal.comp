#version 450
// ReSTIR DI's temporal reuse (Bitterli et al. 2020, Section 4 and Alg. 5; RTXDI's
// TemporalResampling): this frame's candidate reservoir (c, at this frame's surface s) combined
// with a final reservoir of the previous frame (p, at its surface q), p's M capped at `cap` times
// c's. The previous frame is this render's frame before (the same camera and lights) or, for a
// render's first frame, the previous animation frame's last one (its reservoirs carried over by
// the method, src/methods/restir/mod.rs). Which pixel's: s's point projected through the previous
// camera, the pixel it falls in; where that pixel's surface differs from s (shading normals'
// cosine under normal_cos, or its distance from the previous camera off s's by more than
// depth_tolerance of the larger: RTXDI's 0.5 and 0.1), up to 8 more pixels picked at random
// among it and its 8 neighbours (RTXDI's search), the first alike taken, else none (a
// disocclusion: no history). Across animation frames
// p's light entry is translated into this frame's table (EntryTranslation; a light gone keeps
// p's M and drops its sample, as RTXDI does). The result keeps restir.glsl's invariant.
// Combinations:
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
// at q take the previous frame's map, emission and lights and its camera position, s's this
// frame's. Geometry stands still, so visibility from q is traced in this frame's BVH exactly.

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
    vec4 previous_camera_position; // w: tan(fov_y / 2)
    vec4 previous_camera_forward;  // w: width / height
    vec4 previous_camera_right;
    vec4 previous_camera_up;
    uint frame;
    uint seed;
    float cap;        // the previous reservoir's M at most cap times this one's
    uint combination; // COMBINATION_* (restir.glsl)
    uint previous_env_base; // the previous frame's map in PreviousEnvTexels, in texels
    uint history;     // HISTORY_*
    float normal_cos; // the surface test (see the header)
    float depth_tolerance;
} params;

// No previous frame: nothing is reused.
const uint HISTORY_NONE = 0u;
// This render's previous frame: the same light table.
const uint HISTORY_RENDER = 1u;
// The previous animation frame's last: its entries translated (EntryTranslation).
const uint HISTORY_ANIMATION = 2u;

// Each entry of the previous frame's light table in this frame's, NO_LIGHT where the light is
// gone (read with HISTORY_ANIMATION only).
layout(set = 0, binding = 19, std430) readonly buffer EntryTranslation { uint entry_translation[]; };

// Dimensions of the selection's random number and of the search's offsets (the pass has its
// own seed: kernels.rs).
const uint TEMPORAL_DIMENSION = 1u;
const uint SEARCH_DIMENSION = 2u;
// The back-projected pixel, then up to this many tries at offsets int((u - 0.5) SEARCH_RADIUS)
// (-1, 0 or 1 in each axis, -2 at u = 0), RTXDI's.
const uint SEARCH_TRIES = 8u;
const float SEARCH_RADIUS = 4.0;

// Where the previous camera saw p, in pixels (continuous), and p's distance from it; false
// behind the camera.
bool project_to_previous(vec3 p, out vec2 xy, out float distance_to_camera) {
    vec3 d = p - params.previous_camera_position.xyz;
    distance_to_camera = length(d);
    float z = dot(d, params.previous_camera_forward.xyz);
    if (!(z > 0.0)) return false;
    float t = params.previous_camera_position.w;
    float a = dot(d, params.previous_camera_right.xyz) / (z * t * params.previous_camera_forward.w);
    float b = dot(d, params.previous_camera_up.xyz) / (z * t);
    vec2 size = vec2(scene.size.xy);
    // camera.glsl's mapping inverted; far outside the image clamped (the search then finds
    // nothing there).
    xy = clamp(vec2((a + 1.0) * 0.5 * size.x, (1.0 - b) * 0.5 * size.y), vec2(-64.0),
               size + 64.0);
    return true;
}

// The previous frame's pixel whose surface is alike s's (the header's test), or -1.
int find_previous_pixel(RestirPoint s, uint index, out RestirPoint q) {
    vec2 xy;
    float expected;
    q.valid = false;
    if (!project_to_previous(s.p, xy, expected)) return -1;
    ivec2 centre = ivec2(floor(xy));
    ivec2 size = ivec2(scene.size.xy);
    for (uint i = 0u; i <= SEARCH_TRIES; ++i) {
        ivec2 at = centre;
        if (i > 0u) {
            vec2 u = vec2(random(params.seed, index, params.frame, SEARCH_DIMENSION + 2u * i),
                          random(params.seed, index, params.frame, SEARCH_DIMENSION + 2u * i + 1u));
            at += ivec2((u - 0.5) * SEARCH_RADIUS);
        }
        if (any(lessThan(at, ivec2(0))) || any(greaterThanEqual(at, size))) continue;
        int j = at.y * size.x + at.x;
        RestirPoint candidate = restir_point_from_surface(previous_surfaces[j],
                                                          restir_previous_camera);
        if (!candidate.valid || dot(candidate.n, s.n) < params.normal_cos) continue;
        float depth = length(candidate.p - restir_previous_camera);
        if (abs(depth - expected) > params.depth_tolerance * max(depth, expected)) continue;
        q = candidate;
        return j;
    }
    return -1;
}

void main() {
    uvec2 pixel = gl_GlobalInvocationID.xy;
    if (pixel.x >= scene.size.x || pixel.y >= scene.size.y) return;
    uint index = pixel.y * scene.size.x + pixel.x;
    restir_previous_env_base = params.previous_env_base;
    restir_previous_camera = params.previous_camera_position.xyz;
    RestirPoint s = restir_point_from_gbuffer(index);
    Reservoir current = reservoirs[index];
    if (!s.valid || params.history == HISTORY_NONE) return;
    RestirPoint q;
    int found = find_previous_pixel(s, index, q);
    Reservoir previous = empty_reservoir(0.0);
    if (found >= 0) {
        // Member by member (a block's struct in a conditional: spirv-val rejects glslang's store).
        previous.sample_point = final_reservoirs[found].sample_point;
        previous.weights = final_reservoirs[found].weights;
    }
    uint e_previous = floatBitsToUint(previous.sample_point.w);
    if (params.history == HISTORY_ANIMATION && e_previous != NO_LIGHT) {
        e_previous = entry_translation[e_previous];
        if (e_previous == NO_LIGHT) previous.weights.x = 0.0;
        previous.sample_point.w = uintBitsToFloat(e_previous);
    }

    float m_current = current.weights.y;
    float m_previous = q.valid ? min(previous.weights.y, params.cap * m_current) : 0.0;
    uint e_current = floatBitsToUint(current.sample_point.w);
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
