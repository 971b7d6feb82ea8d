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

layout(push_constant) uniform GatherParams {
    uint vpl_begin;   // shade VPL slots [vpl_begin, vpl_end)
    uint vpl_end;
    float g_clamp;    // 0: no clamp; else the geometry term is min(G, g_clamp)
    uint interleave;  // k (1: every pixel shades every VPL)
} params;

// Each pixel's interleaved estimate of this frame (k > 1 only).
layout(set = 0, binding = 15, std430) buffer VplRadiance { vec4 vpl_radiance[]; };

#define CHUNK 64u
shared Vpl chunk[CHUNK];

vec3 shade_from_vpl(Vpl v, vec3 x, vec3 origin, vec3 n, vec3 side, vec3 wo, Material m) {
    uint kind = vpl_kind(v);
    if (kind == VPL_NONE) return vec3(0.0);
    vec3 d = v.position.xyz - x;
    float dist2 = dot(d, d);
    if (dist2 <= 0.0) return vec3(0.0);
    vec3 w = d * inversesqrt(dist2);
    float cos_x = dot(n, w);
    if (cos_x <= 0.0 || dot(side, w) <= 0.0) return vec3(0.0);
    vec3 fx = bsdf_eval(m, n, wo, w);
    if (max(max(fx.r, fx.g), fx.b) <= 0.0) return vec3(0.0);

    // Emitted toward x per unit G, and G = cos_v cos_x / d^2 (cos_v = 1 for point lights).
    vec3 emitted;
    float cos_v = 1.0;
    vec3 target = v.position.xyz;
    if (kind == VPL_SURFACE) {
        cos_v = dot(v.normal.xyz, -w);
        if (cos_v <= 0.0) return vec3(0.0);
        Material mv = materials[floatBitsToUint(v.normal.w)];
        emitted = v.power.rgb * bsdf_eval(mv, v.normal.xyz, v.incident.xyz, -w);
        target = offset_origin(target, v.normal.xyz);
    } else if (kind == VPL_AREA) {
        cos_v = dot(v.normal.xyz, -w);
        if (cos_v <= 0.0) return vec3(0.0);
        emitted = v.power.rgb * INV_PI;
    } else if (kind == VPL_SPOT) {
        Light l;
        l.direction = v.normal;
        l.cone = vec4(v.power.w, 0.0, 0.0, 0.0);
        emitted = v.power.rgb * spot_falloff(l, -w);
    } else {
        emitted = v.power.rgb;
    }
    float g = cos_v * cos_x / dist2;
    if (params.g_clamp > 0.0) g = min(g, params.g_clamp);
    vec3 contribution = emitted * fx * g;
    if (max(max(contribution.r, contribution.g), contribution.b) <= 0.0) return vec3(0.0);
    if (trace_any(origin, target - origin, 0.9999)) return vec3(0.0);
    return contribution;
}

void main() {
    uvec2 pixel = gl_GlobalInvocationID.xy;
    bool inside = pixel.x < scene.size.x && pixel.y < scene.size.y;
    uint index = inside ? pixel.y * scene.size.x + pixel.x : 0u;
    GBufferTexel g = gbuffer[index];
    bool shading = inside && g.position.w >= 0.0;

    vec3 x = g.position.xyz;
    vec3 wo = -g.direction.xyz;
    vec3 ng = g.geometric_normal.xyz;
    vec3 side = dot(wo, ng) >= 0.0 ? ng : -ng;
    vec3 ns = g.shading_normal.xyz;
    vec3 n = dot(ns, side) >= 0.0 ? ns : -ns;
    vec3 origin = offset_origin(x, side);
    Material m = materials[shading ? floatBitsToUint(g.shading_normal.w) : 0u];

    uint k = max(params.interleave, 1u);
    uint subsets = k * k;
    uint subset = (pixel.x % k) + k * (pixel.y % k);
    vec3 sum = vec3(0.0);
    for (uint base = params.vpl_begin; base < params.vpl_end; base += CHUNK) {
        uint slot = base + gl_LocalInvocationIndex;
        if (slot < params.vpl_end) {
            chunk[gl_LocalInvocationIndex] = vpls[slot];
        } else {
            chunk[gl_LocalInvocationIndex].position = vec4(0.0, 0.0, 0.0, uintBitsToFloat(VPL_NONE));
        }
        memoryBarrierShared();
        barrier();
        if (shading) {
            // The first slot of this chunk in my subset, then every subsets-th.
            uint first = (subset + subsets - base % subsets) % subsets;
            for (uint j = first; j < CHUNK; j += subsets) {
                sum += shade_from_vpl(chunk[j], x, origin, n, side, wo, m);
            }
        }
        barrier();
    }
    if (!inside) return;
    if (k == 1u) {
        accumulate_radiance(index, sum);
    } else {
        vpl_radiance[index] += vec4(sum * float(subsets), 0.0);
    }
}
