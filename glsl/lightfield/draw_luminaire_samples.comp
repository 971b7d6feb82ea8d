#version 450
// The restricted-CDF sampler (luminaire_tables.glsl) on its own, for its tests: draw k in image
// m's window writes (s, t, realised pdf, search steps), from random numbers (seed, k); a
// window holding nothing writes pdf 0. One invocation per k.

#extension GL_GOOGLE_include_directive : require

layout(local_size_x = 64, local_size_y = 1, local_size_z = 1) in;

#include "sampling.glsl"
#include "luminaire_tables.glsl"

layout(set = 0, binding = 33, std430) writeonly buffer LuminaireDraws { vec4 draws[]; };

layout(push_constant) uniform DrawParams {
    vec4 window;  // (s0, s1, t0, t1), texel units
    uint m;
    uint width;
    uint height;
    uint count;
    uint seed;
    uint search;
} params;

void main() {
    uint k = gl_GlobalInvocationID.x;
    if (k >= params.count) return;
    LuminaireImage im = LuminaireImage(params.m, params.width, params.height);
    vec2 u = vec2(random(params.seed, k, 0u, 0u), random(params.seed, k, 0u, 1u));
    vec2 st;
    uvec2 texel;
    float pdf;
    uint steps;
    if (!draw_restricted(im, params.window, u, params.search, st, texel, pdf, steps)) pdf = 0.0;
    draws[k] = vec4(st, pdf, float(steps));
}
