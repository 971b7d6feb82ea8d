#version 450
// ReSTIR DI's spatial reuse (Bitterli et al. 2020, Section 4, Alg. 4 and 6): each pixel's
// reservoir combined with those of k random neighbours within R pixels (uniform over the
// disk), a neighbour rejected where its surface differs (normals more than about 25 degrees
// apart, camera distances more than 10% apart: the paper's heuristics) or the camera missed.
// Weights p^(y) W M with p^ at this pixel's surface. Unbiased (the default): 1 / Z, Z the M of
// the reservoirs (this pixel's and the neighbours' taken) whose surface could have produced y,
// p^ > 0 there and y visible from it (a shadow ray from each but the one that produced y).
// Biased: Z = the sum of every M taken. The chosen sample's visibility from this pixel is
// tested in both (restir.glsl's invariant), and the result is the frame's final reservoir,
// stored with this frame's surface for the next frame's temporal pass.
//
// Loop budget: at most 16 neighbours (the setting's range): in the unbiased mode a shadow ray
// each and one for the pixel (k + 1 rays), in the biased mode one for the pixel.

#extension GL_GOOGLE_include_directive : require

layout(local_size_x = 8, local_size_y = 8, local_size_z = 1) in;

#include "bvh.glsl"
#include "scene.glsl"
#include "sampling.glsl"
#include "bsdf.glsl"
#include "lights.glsl"
#include "gbuffer.glsl"
#include "restir.glsl"

layout(push_constant) uniform SpatialParams {
    uint frame;
    uint seed;
    uint neighbours;  // k, at most MAX_NEIGHBOURS
    float radius;     // R, pixels
    uint unbiased;    // 1: 1 / Z with visibility; 0: 1 / (sum of M)
    float normal_cos; // a neighbour's normal at least this close (cosine) ...
    float depth_tolerance;  // ... and its camera distance within this fraction
    uint _pad;
} params;

const uint MAX_NEIGHBOURS = 16u;
// Random dimensions: 2 + 3 j .. 4 + 3 j for neighbour j (position, selection); the pass has
// its own seed (kernels.rs).
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

    // The reservoirs taken: index 0 this pixel's, then the neighbours'.
    uint taken[MAX_NEIGHBOURS + 1u];
    taken[0] = index;
    uint count = 1u;
    float weight_sum = 0.0;
    uint chosen = 0u;
    uint entry = floatBitsToUint(own.sample_point.w);
    vec3 y = own.sample_point.xyz;
    float target = own.weights.z;
    float m_sum = own.weights.y;
    reservoir_take(weight_sum, own.weights.z * own.weights.x * own.weights.y, 0.0);

    for (uint j = 0u; j < params.neighbours; ++j) {
        uint dim = SPATIAL_DIMENSION + 3u * j;
        float r = params.radius * sqrt(random(params.seed, index, params.frame, dim));
        float phi = 2.0 * PI * random(params.seed, index, params.frame, dim + 1u);
        ivec2 q = ivec2(pixel) + ivec2(round(r * vec2(cos(phi), sin(phi))));
        if (q.x < 0 || q.y < 0 || q.x >= int(scene.size.x) || q.y >= int(scene.size.y)) continue;
        uint qi = uint(q.y) * scene.size.x + uint(q.x);
        if (qi == index) continue;
        RestirPoint n = restir_point_from_gbuffer(qi);
        if (!n.valid || dot(n.n, s.n) < params.normal_cos
            || abs(camera_distance(n.p) - depth) > params.depth_tolerance * depth) continue;
        Reservoir other = reservoirs[qi];
        uint other_entry = floatBitsToUint(other.sample_point.w);
        float other_target = other.weights.x > 0.0
            ? restir_target(s, other_entry, other.sample_point.xyz) : 0.0;
        float w = other_target * other.weights.x * other.weights.y;
        taken[count] = qi;
        m_sum += other.weights.y;
        if (reservoir_take(weight_sum, w, random(params.seed, index, params.frame, dim + 2u))) {
            chosen = count;
            entry = other_entry;
            y = other.sample_point.xyz;
            target = other_target;
        }
        ++count;
    }

    Reservoir result = empty_reservoir(m_sum);
    if (weight_sum > 0.0 && !isinf(weight_sum)) {
        bool visible = chosen == 0u ? true : restir_visible(s, entry, y);
        float z = m_sum;
        if (params.unbiased != 0u) {
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
        result.weights.x = visible && z > 0.0 ? weight_sum / (z * target) : 0.0;
    }
    final_reservoirs[index] = result;
}
