#version 450
// Segovia 06 Section 4.1: the light-selection table bir's walk starts light paths from,
// weighted by each light's contribution to what the camera sees (RowTotals, the sums of
// estimate_light_contributions.comp) plus a floor, floor_fraction times the mean, so no light
// that can contribute has zero probability. Written as LightEntries are (an integer CDF over
// 31-bit random numbers, src/sampling/distribution.rs: the realised probability is exactly
// (upper - previous upper) / 2^31, and that is what the walk divides by). One invocation: the
// table is small and the running sum must be sequential for the exact bounds anyway.

#extension GL_GOOGLE_include_directive : require

layout(local_size_x = 1, local_size_y = 1, local_size_z = 1) in;

// bvh.glsl only because the scene bindings come as one set (GpuScene::bindings).
#include "bvh.glsl"
#include "scene.glsl"

layout(set = 0, binding = 20, std430) readonly buffer RowTotals { float totals[]; };
layout(set = 0, binding = 23, std430) writeonly buffer CameraLightEntries { LightEntry camera_entries[]; };

layout(push_constant) uniform CdfParams {
    uint entries;
    float floor_fraction;
} params;

void main() {
    uint n = params.entries;
    float sum = 0.0;
    for (uint l = 0u; l < n; ++l) sum += max(totals[l], 0.0);
    float delta = sum > 0.0 ? params.floor_fraction * sum / float(n) : 1.0;
    float all = sum + delta * float(n);
    float running = 0.0;
    uint previous = 0u;
    for (uint l = 0u; l < n; ++l) {
        running += max(totals[l], 0.0) + delta;
        uint upper = l + 1u == n ? 0x80000000u
                                 : min(uint(round(running / all * 2147483648.0)), 0x80000000u);
        upper = max(upper, previous);
        LightEntry e = light_entries[l];
        e.upper = upper;
        e.probability = float(upper - previous) / 2147483648.0;
        camera_entries[l] = e;
        previous = upper;
    }
}
