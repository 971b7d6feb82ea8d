#version 450
// bir's side weights for `both` (an irad addition to Segovia 06): the image is a_s times the
// standard side's estimate plus a_r times the reverse side's, a_s + a_r = 1. Any weights fixed
// before a batch's random numbers are drawn keep it unbiased; the paper's plain union is
// a_s = a_r = 1/2, which where one side starves (the U office's standard VPLs, which rarely
// pass the door; the halogen office's reverse VPLs, which rarely land in the lit pool) shows
// that side's heavy tail at half weight.
//
// Both sides' candidates estimate the same total camera power: T_s, the sum of the standard
// candidates' power estimates, and T_r, the reverse ones'. A starving side is one whose mean
// rests on rare huge batches, so its typical batch brings less than the other side's: after
// each batch this kernel counts whether T_s > T_r (a tie counts 1/2), takes the fraction f of
// the batches so far in which the standard side brought more (with a prior of two wins and two
// losses: f = (wins + 2) / (batches + 4)), and sets a_s = f^4 / (f^4 + (1 - f)^4), clamped to
// [min_weight, 1 - min_weight] so neither side is ever dropped. Where the sides are alike
// (the Cornell box) f hovers about 1/2; where one starves a_s goes to the clamp.
//
// Why sharpened: the resampling draws each side's VPLs about in proportion to its weight times
// its power total (plus the floor), so the resampling's part of the union's variance is about
// a_s V_s + a_r V_r, linear in a_s and least at the better side alone; the candidates' own
// variance, a_s^2 Var(S) + a_r^2 Var(R), is least at inverse-variance weights in between. Which
// dominates is measured, not derived: on the offices the better side alone beats the union.
// A standard VPL no reverse VPL can reach keeps weight 1 (resample_vpls.comp) but is drawn in
// proportion to a_s w, so at a small a_s its draws carry up to 1 / a_s more power; drawing it
// at weight 1 instead measured worse on the U office (resample_vpls.comp). So did four
// unrecorded pilot batches before frame 0 that set the weights before any frame is shaded at
// the prior's 1/2 (scenes/suites/bir-convergence.toml, sixth run). Measured (irad bench suite,
// 128x96, 8 seeds, lavapipe; spread = standard deviation of the renders' image means; relMSE
// against the converged reference):
//   u-office, 2 s / 8 s: plain win fraction (a_s 0.21-0.28): spread 28.6% / 9.1%, relMSE
//     0.123 / 0.054; reverse side alone 10.9% / 4.4%, 0.048 / 0.021; standard alone 80% / 20%;
//   halogen-office: win fraction (a_s 0.82-0.87) 11.3% / 9.3%, relMSE 0.18 / 0.20; standard
//     alone 1.5% / 0.9%, 0.20 / 0.19; reverse alone 45% / 29%.
// The win fraction picks the better side on both offices but weighs the other one too much;
// sharpened, after 40 batches of which 10 won (f = 12 / 44) a_s is 0.019 (clamped to
// min_weight 0.02), after 34 won of 40 (f = 36 / 44) 0.998 (clamped to 0.98).
// Tried first and measured worse: the share of the summed powers (follows the rare huge batches
// back to 1/2), the mean per-batch share (the halogen office's half-starved reverse side still
// brings a third of a typical batch, and at a third of the weight its dark typical renders darkened
// the image by 18% in two renders), and inverse-variance weights (before the rare hit arrives, the
// starving side's near-zero totals look like low variance). Inverse mean squared deviations from
// the pooled mean of both sides (which a starving side's near-zero batches do show) measured no
// better: 11-frame renders at 64x48, 40 seeds, image-mean spread 0.297 against the plain win
// fraction's 0.285 on the U office (final a_s 0.29, the same: the candidates' camera-power totals
// do not see the standard side's tail the image shows) and 0.383 against 0.244 on the halogen
// office. A batch only uses weights set from earlier batches, whose random numbers are independent
// of its own.
//
// SideWeights: [0] = (a_s, a_r, batches the standard side won, batches counted).

#extension GL_GOOGLE_include_directive : require

layout(local_size_x = 1, local_size_y = 1, local_size_z = 1) in;

// The inclusive prefix sums of the batch's power estimates (standard candidates first).
layout(set = 0, binding = 19, std430) readonly buffer Scanned { float scanned[]; };
layout(set = 0, binding = 24, std430) buffer SideWeights { vec4 side; };

layout(push_constant) uniform SideParams {
    uint candidates;
    uint standard;   // candidates [0, standard) are standard VPLs
    float min_weight;
} params;

void main() {
    float all = scanned[params.candidates - 1u];
    float standard_total = params.standard > 0u ? scanned[params.standard - 1u] : 0.0;
    float reverse_total = max(all - standard_total, 0.0);
    vec4 s = side;
    if (all > 0.0 && !isinf(all)) {
        s.z += standard_total > reverse_total ? 1.0
             : (standard_total == reverse_total ? 0.5 : 0.0);
        s.w += 1.0;
        // The win fraction with two batches' prior toward 1/2, sharpened (module comment).
        float f = (s.z + 2.0) / (s.w + 4.0);
        float f4 = f * f * f * f;
        float g = 1.0 - f;
        float a = clamp(f4 / (f4 + g * g * g * g), params.min_weight, 1.0 - params.min_weight);
        s.x = a;
        s.y = 1.0 - a;
    }
    side = s;
}
