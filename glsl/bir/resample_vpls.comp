#version 450
// bir's resampling (Segovia 06 Sections 3.2 and 4.2): from the C candidates of a batch
// (standard VPLs first, then reverse VPLs), N' are drawn with probability proportional to
// their estimated power to the camera times their side's weight (SideWeights) plus a uniform
// floor, q_c = (a_c w_c + delta n_c) / W', W' = sum a w + delta K, K the non-empty
// candidates, delta = floor * sum a w / K (1 when no candidate has power): every VPL that can
// contribute keeps a non-zero probability (the paper's Fig. 3). Systematic sampling: draw k
// takes the candidate whose cumulative interval holds (k + xi) W' / N', one xi per batch, so
// candidate c is drawn N' q_c times in expectation; each draw is a VPL of power
// a_c P_c / (N' q_c), a_c its weight (its side's, or 1 for a standard VPL no reverse VPL
// could reach), the paper's "density times CDF weight, energy times the count chosen", and
// the sum over draws is an unbiased estimate of the weighted sum over candidates. Needs the
// inclusive prefix sums of both rows (Scanned) and their totals.

#extension GL_GOOGLE_include_directive : require

layout(local_size_x = 64, local_size_y = 1, local_size_z = 1) in;

#include "sampling.glsl"
#include "vpl.glsl"
#include "reverse_vpl.glsl"

layout(set = 0, binding = 17, std430) readonly buffer Weights { float weights[]; };
layout(set = 0, binding = 18, std430) writeonly buffer KeptVpls { Vpl kept[]; };
layout(set = 0, binding = 19, std430) readonly buffer Scanned { float scanned[]; };
layout(set = 0, binding = 20, std430) readonly buffer RowTotals { float totals[]; };
// Draws kept per side, over the whole render (for the report).
layout(set = 0, binding = 21, std430) buffer ResampleStats { uint kept_standard; uint kept_reverse; };
// x, y: the standard and reverse sides' weights (sum 1); z, w: batches the standard side won
// and batches counted (update_side_weights.comp).
layout(set = 0, binding = 24, std430) readonly buffer SideWeights { vec4 side; };

layout(push_constant) uniform ResampleParams {
    uint draws;           // N' of this batch
    uint kept_offset;     // where they go in KeptVpls
    uint candidates;      // C
    uint standard;        // S: candidates [0, S) are Vpls[standard_begin + c]
    uint standard_begin;
    float unused;
    float floor_fraction;
    uint seed;
} params;

// The weighted inclusive cumulative of candidate c: a_s S(c) for the standard part, then
// a_s S(S - 1) + a_r (S(c) - S(S - 1)).
float weighted(uint c) {
    if (c < params.standard) return side.x * scanned[c];
    float standard_sum = params.standard > 0u ? scanned[params.standard - 1u] : 0.0;
    return side.x * standard_sum + side.y * (scanned[c] - standard_sum);
}

float cumulative(uint c, float delta) {  // inclusive, floored
    return weighted(c) + delta * scanned[params.candidates + c];
}

void main() {
    uint k = gl_GlobalInvocationID.x;
    if (k >= params.draws) return;
    Vpl none;
    none.position = vec4(0.0, 0.0, 0.0, uintBitsToFloat(VPL_NONE));
    none.normal = vec4(0.0);
    none.power = vec4(0.0);
    none.incident = vec4(0.0);
    float nonempty = totals[1];
    if (nonempty < 0.5 || params.candidates == 0u) {
        kept[params.kept_offset + k] = none;
        return;
    }
    float total = weighted(params.candidates - 1u);
    float delta = total > 0.0 ? params.floor_fraction * total / nonempty : 1.0;
    float all = total + delta * nonempty;
    float xi = random(params.seed, 0u, 0x72736d70u, 0u);
    float target = (float(k) + xi) / float(params.draws) * all;
    // The first candidate whose inclusive cumulative exceeds the target.
    uint lo = 0u;
    uint hi = params.candidates - 1u;
    while (lo < hi) {
        uint mid = (lo + hi) / 2u;
        if (cumulative(mid, delta) > target) hi = mid; else lo = mid + 1u;
    }
    uint c = lo;
    float a = c < params.standard ? side.x : side.y;
    float q = (a * weights[c] + delta * weights[params.candidates + c]) / all;
    if (!(q > 0.0)) {
        kept[params.kept_offset + k] = none;
        return;
    }
    Vpl v;
    if (c < params.standard) {
        v = vpls[params.standard_begin + c];
        // No reverse VPL could land where find_uncovered_vpls.comp marked: weight 1. The draw
        // probability q need not follow the weight; any q > 0 keeps the draw unbiased. Drawing
        // them at weight 1 too (q following a = 1) measured worse on u-office and was dropped
        // (scenes/suites/bir-convergence.toml, fifth run): their power estimates are the noisy
        // ones (few camera points see them), and the draws would follow that noise 1/a_s more.
        if (v.incident.w > 0.5) a = 1.0;
        atomicAdd(kept_standard, 1u);
    } else {
        v = reverse_vpls[c - params.standard];
        atomicAdd(kept_reverse, 1u);
    }
    v.power.rgb *= a / (float(params.draws) * q);
    kept[params.kept_offset + k] = v;
}
