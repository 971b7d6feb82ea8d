#version 450
// Instant radiosity's gathering (Keller 97 Section 3, "one shadowed image per VPL" done in
// compute): each workgroup shades one 8 x 8 tile of the G-buffer; VPLs stream through shared
// memory 64 at a time; per (pixel, VPL) pair: the BSDF at both ends, the geometry term and one
// any-hit shadow ray. Optional clamp of the geometry term (Keller's weak singularity; biased,
// off unless g_clamp > 0). Interleaved sampling (Keller and Heidrich 2001): with k > 1, pixel
// (x, y) shades only the VPLs of subset (x mod k) + k (y mod k), VPL v being in subset
// v mod k^2, weighted by k^2, and adds into VplRadiance (cleared per frame) instead:
// filter_interleaved.comp restores a full estimate per pixel and accumulates it.

#extension GL_GOOGLE_include_directive : require

layout(local_size_x = 8, local_size_y = 8, local_size_z = 1) in;

#include "bvh.glsl"
#include "scene.glsl"
#include "sampling.glsl"
#include "bsdf.glsl"
#include "lights.glsl"
#include "gbuffer.glsl"
#include "radiance.glsl"
#include "vpl.glsl"
#include "vpl_shading.glsl"

layout(push_constant) uniform GatherParams {
    uint vpl_begin;   // shade VPL slots [vpl_begin, vpl_end)
    uint vpl_end;
    float g_clamp;    // 0: no clamp; else the geometry term is min(G, g_clamp)
    uint interleave;  // k (1: every pixel shades every VPL)
    float weight;     // multiplies every VPL's contribution (bir's share of each side)
} params;

// Each pixel's interleaved estimate of this frame (k > 1 only).
layout(set = 0, binding = 15, std430) buffer VplRadiance { vec4 vpl_radiance[]; };

#define CHUNK 64u
shared Vpl chunk[CHUNK];
shared Material chunk_materials[CHUNK];  // vpl_material of each

void main() {
    uvec2 pixel = gl_GlobalInvocationID.xy;
    bool inside = pixel.x < scene.size.x && pixel.y < scene.size.y;
    uint index = inside ? pixel.y * scene.size.x + pixel.x : 0u;
    GBufferTexel g = gbuffer[index];
    vec3 wo, side, n;
    bool shading = gbuffer_surface(g, wo, side, n) && inside;
    vec3 x = g.position.xyz;
    vec3 origin = offset_origin(x, side);
    Material m = gbuffer_material(g);

    uint k = max(params.interleave, 1u);
    uint subsets = k * k;
    uint subset = (pixel.x % k) + k * (pixel.y % k);
    vec3 sum = vec3(0.0);
    for (uint base = params.vpl_begin; base < params.vpl_end; base += CHUNK) {
        uint slot = base + gl_LocalInvocationIndex;
        if (slot < params.vpl_end) {
            Vpl v = vpls[slot];
            chunk[gl_LocalInvocationIndex] = v;
            chunk_materials[gl_LocalInvocationIndex] = vpl_material(v);
        } else {
            chunk[gl_LocalInvocationIndex].position = vec4(0.0, 0.0, 0.0, uintBitsToFloat(VPL_NONE));
            chunk_materials[gl_LocalInvocationIndex] = materials[0];
        }
        memoryBarrierShared();
        barrier();
        if (shading) {
            // The first slot of this chunk in my subset, then every subsets-th.
            uint first = (subset + subsets - base % subsets) % subsets;
            for (uint j = first; j < CHUNK; j += subsets) {
                sum += shade_from_vpl(chunk[j], chunk_materials[j], x, origin, n, side, wo, m,
                                      params.g_clamp);
            }
        }
        barrier();
    }
    if (!inside) return;
    sum *= params.weight;
    if (k == 1u) {
        accumulate_radiance(index, sum);
    } else {
        vpl_radiance[index] += vec4(sum * float(subsets), 0.0);
    }
}
