#version 450
// Lu 14 Alg. 1 line 10: the frame's light samples, pre-generated per cube face and shared by
// every pixel: for face f and sample k, scrambled Halton point (first + k) picks a row of
// the face by binary search over the face's row scan (dimension 0), a texel in the row by
// binary search over the row's scan (dimension 1), and (u, v) uniformly in the texel
// (dimensions 2-3). Each sample stores its direction and pdf_L(w | f) (env_cube.glsl); a face
// with no weight stores pdf 0. One invocation per (sample, face); slot
// (set * 6 + f) * per_face + k. The samples of a face come in windows of `window` (what one
// pixel reads, shade_env.comp), each window the prefix of its own independently scrambled
// sequence: windows of one sequence share its scrambling, and their errors moved together
// (sun-behind, 64 windows: the image mean's spread over seeds fell only 1.6x, not ~8x).

#extension GL_GOOGLE_include_directive : require

layout(local_size_x = 64, local_size_y = 1, local_size_z = 1) in;

#include "sampling.glsl"
#include "halton.glsl"
#include "cubemap.glsl"
#include "env_cube.glsl"

layout(set = 0, binding = 24, std430) writeonly buffer EnvSamples { vec4 env_samples[]; };

layout(push_constant) uniform SampleParams {
    uint resolution;  // R
    uint per_face;    // samples per face
    uint first;       // Halton index of sample 0
    uint seed;
    uint set;         // which of the sample sets (alpha uses two, independently scrambled)
    uint window;      // samples per window (per_face when there is one window)
} params;

void main() {
    uint k = gl_GlobalInvocationID.x;
    uint f = gl_GlobalInvocationID.y;
    if (k >= params.per_face || f >= 6u) return;
    uint r = params.resolution;
    uint slot = (params.set * 6u + f) * params.per_face + k;
    float total = cube_face_totals[f];
    if (!(total > 0.0)) {
        env_samples[slot] = vec4(0.0, 1.0, 0.0, 0.0);
        return;
    }
    uint window = k / params.window;
    uint index = params.first + k % params.window;
    uint seed = window == 0u ? params.seed : pcg_hash(params.seed ^ pcg_hash(window));
    vec4 u = vec4(halton(0u, index, seed), halton(1u, index, seed),
                  halton(2u, index, seed), halton(3u, index, seed));
    uint j = cube_search(true, f * r, r, u.x * total);
    uint row = f * r + j;
    uint i = cube_search(false, row * r, r, u.y * cube_row_cdf[row * r + r - 1u]);
    float p = cube_texel_probability(f, i, j, r);
    float s = 2.0 / float(r);
    vec2 uv = vec2(-1.0 + s * (float(i) + u.z), -1.0 + s * (float(j) + u.w));
    vec3 d = normalize(cube_face_point(f, uv.x, uv.y));
    env_samples[slot] = vec4(d, p * cube_uv_to_solid_angle(uv, s * s));
}
