#version 450
// The power a candidate VPL brings to the camera (Segovia 06 Section 3.2, 4.2), for bir's
// resampling: the camera response to the VPL, estimated with M length-2 camera paths: M
// G-buffer points at pseudo-random pixels, each shaded by the VPL (one shadow ray), the
// luminance summed and scaled by pixels / M. Writes row 0 of Weights (the estimate, times
// `scale`) and row 1 (1 for a VPL, 0 for an empty slot: only those get the CDF's floor).
//
// Numbers: pixel m of candidate c is pcg(seed, c, m) mod the pixel count.
//
// The M camera points are split over dispatches, [sample_begin, sample_end) each (a shadow
// ray per point; lavapipe's loop budget, docs/DESIGN.md "The loop budget"): the first writes its share of
// the estimate, the others add theirs.

#extension GL_GOOGLE_include_directive : require

layout(local_size_x = 64, local_size_y = 1, local_size_z = 1) in;

#include "bvh.glsl"
#include "scene.glsl"
#include "sampling.glsl"
#include "bsdf.glsl"
#include "lights.glsl"
#include "gbuffer.glsl"
#include "vpl.glsl"
#include "vpl_shading.glsl"

// Two rows of `row_length`: the weights, then the non-empty flags.
layout(set = 0, binding = 17, std430) buffer Weights { float weights[]; };

layout(push_constant) uniform PowerParams {
    uint count;        // candidates in this dispatch
    uint source_begin; // first slot of Vpls they come from
    uint offset;       // their first candidate index
    uint row_length;   // candidates in all
    uint samples;      // M camera points per candidate
    uint seed;
    uint pixels;
    float scale;       // the side's weight (standard VPLs' 1/2 under `both`)
    uint sample_begin; // this dispatch's camera points
    uint sample_end;
} params;

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= params.count) return;
    uint c = params.offset + i;
    Vpl v = vpls[params.source_begin + i];
    if (vpl_kind(v) == VPL_NONE) {
        weights[c] = 0.0;
        weights[params.row_length + c] = 0.0;
        return;
    }
    Material mv = vpl_material(v);
    float sum = 0.0;
    for (uint m = params.sample_begin; m < min(params.sample_end, params.samples); ++m) {
        uint pixel = hash4(params.seed, c, m, 0x706f7772u) % params.pixels;
        GBufferTexel g = gbuffer[pixel];
        vec3 wo, side, n;
        if (!gbuffer_surface(g, wo, side, n)) continue;
        vec3 x = g.position.xyz;
        Material mat = gbuffer_material(g);
        sum += luminance(shade_from_vpl(v, mv, x, offset_origin(x, side), n, side, wo, mat, 0.0));
    }
    float w = sum * params.scale * float(params.pixels) / float(max(params.samples, 1u));
    if (params.sample_begin > 0u) w += weights[c];
    weights[c] = (isnan(w) || isinf(w)) ? 0.0 : w;
    weights[params.row_length + c] = 1.0;
}
