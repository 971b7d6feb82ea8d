#version 450
// bir's side weights for `both` (an irad addition to Segovia 06): the image is a_s times the
// standard side's estimate plus a_r times the reverse side's, a_s + a_r = 1. Any fixed
// weights keep it unbiased; the paper's plain union is a_s = a_r = 1/2, which where one side
// starves (the U office's standard VPLs, the halogen office's reverse ones) shows that side's
// typical, far too dark realisations at half weight. So after each batch the weights move
// toward the sides' shares of the power they have brought to the camera so far (running sums
// of the power estimates), clamped to [min_weight, 1 - min_weight] so neither side is ever
// dropped; a batch only uses weights set from earlier batches, whose random numbers are
// independent of its own, so each batch stays unbiased.

#extension GL_GOOGLE_include_directive : require

layout(local_size_x = 1, local_size_y = 1, local_size_z = 1) in;

layout(set = 0, binding = 19, std430) readonly buffer Scanned { float scanned[]; };
layout(set = 0, binding = 24, std430) buffer SideWeights { vec4 side; };

layout(push_constant) uniform SideParams {
    uint candidates;
    uint standard;
    float min_weight;
} params;

void main() {
    float all = scanned[params.candidates - 1u];
    float standard_sum = params.standard > 0u ? scanned[params.standard - 1u] : 0.0;
    float reverse_sum = max(all - standard_sum, 0.0);
    vec4 s = side;
    s.z += standard_sum;
    s.w += reverse_sum;
    float sum = s.z + s.w;
    if (sum > 0.0) {
        float a = clamp(s.z / sum, params.min_weight, 1.0 - params.min_weight);
        s.x = a;
        s.y = 1.0 - a;
    }
    side = s;
}
