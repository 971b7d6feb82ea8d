#version 450
// Segovia 06 Section 4.1: the light-selection table bir's walk starts light paths from,
// weighted by each light's contribution to what the camera sees (RowTotals, the sums of
// estimate_light_contributions.comp) plus a floor, floor_fraction times the mean, so no light
// that can contribute has zero probability. Written as LightEntries are (an integer CDF over
// 31-bit random numbers, src/sampling/distribution.rs: the realised probability is exactly
// (upper - previous upper) / 2^31, and that is what the walk divides by). One invocation: the
// running sum must be sequential for the exact, monotone bounds. Its two walks over the lights
// (phase 0 sums them, phase 1 writes the table) go in ranges of `count` lights a dispatch, the
// sums carried between dispatches in CdfState, so lavapipe's loop budget (65535 iterations an
// invocation) never cuts a table of many lights short; the results are the same bits whatever
// the split.

#extension GL_GOOGLE_include_directive : require

layout(local_size_x = 1, local_size_y = 1, local_size_z = 1) in;

// bvh.glsl only because the scene bindings come as one set (GpuScene::bindings).
#include "bvh.glsl"
#include "scene.glsl"

layout(set = 0, binding = 20, std430) readonly buffer RowTotals { float totals[]; };
layout(set = 0, binding = 21, std430) buffer CdfState {
    float carried_sum;       // phase 0: the totals so far
    float carried_running;   // phase 1: the weights so far
    uint carried_previous;   // phase 1: the last upper bound written
};
layout(set = 0, binding = 23, std430) writeonly buffer CameraLightEntries { LightEntry camera_entries[]; };

layout(push_constant) uniform CdfParams {
    uint entries;
    float floor_fraction;
    uint first;  // the first light this dispatch takes
    uint count;  // how many it takes at most
    uint phase;  // 0: sum the totals; 1: write the table
} params;

void main() {
    uint n = params.entries;
    uint end = min(n, params.first + params.count);
    if (params.phase == 0u) {
        float sum = params.first == 0u ? 0.0 : carried_sum;
        for (uint l = params.first; l < end; ++l) sum += max(totals[l], 0.0);
        carried_sum = sum;
        return;
    }
    float delta = carried_sum > 0.0 ? params.floor_fraction * carried_sum / float(n) : 1.0;
    float all = carried_sum + delta * float(n);
    float running = params.first == 0u ? 0.0 : carried_running;
    uint previous = params.first == 0u ? 0u : carried_previous;
    for (uint l = params.first; l < end; ++l) {
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
    carried_running = running;
    carried_previous = previous;
}
