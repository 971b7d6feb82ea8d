// The accumulation buffer every method adds its per-frame estimates into (sums; the host
// divides by the frame count), and the counter of non-finite estimates a kernel dropped.
// Bindings 11 and 12.
#ifndef RADIANCE_GLSL
#define RADIANCE_GLSL

layout(set = 0, binding = 11, std430) buffer Radiance { vec4 radiance[]; };
layout(set = 0, binding = 12, std430) buffer Diagnostics { uint nonfinite_estimates; };

// Counts an estimate a kernel dropped for being NaN or Inf (the host reports the count). A
// kernel that drops one before it is an estimate (restir's reservoir whose weights left f32's
// range) counts it here too, so the record warns as it does for the others.
void count_nonfinite_estimate() {
    atomicAdd(nonfinite_estimates, 1u);
}

// Adds one estimate to the pixel's sum; a NaN or Inf estimate is counted and dropped, so no
// non-finite value ever reaches an image.
void accumulate_radiance(uint pixel, vec3 estimate) {
    if (any(isnan(estimate)) || any(isinf(estimate))) {
        // Inline rather than a call: the kernels that only accumulate keep their SPIR-V.
        atomicAdd(nonfinite_estimates, 1u);
        return;
    }
    radiance[pixel] += vec4(estimate, 0.0);
}

#endif
