#version 450
// The VPL light at the vertices of one level of the clamp's compensation paths
// (include/compensation.glsl): per vertex y, every VPL of slots [vpl_begin, vpl_end) through
// vpl_shading.glsl, its geometry term clamped at b (0 at the last level: unclamped, so the
// recursion ends without bias), times the vertex's throughput and `weight`, added into its
// pixel. The vertices are packed (an atomic counter), so a workgroup past the level's count
// exits at once and the others run with their lanes full; VPLs stream through shared memory
// 64 at a time, as in accumulate_vpls_tiled.comp.

#extension GL_GOOGLE_include_directive : require

layout(local_size_x = 64, local_size_y = 1, local_size_z = 1) in;

#include "bvh.glsl"
#include "scene.glsl"
#include "sampling.glsl"
#include "bsdf.glsl"
#include "lights.glsl"
#include "radiance.glsl"
#include "vpl.glsl"
#include "vpl_shading.glsl"
#include "compensation.glsl"

layout(push_constant) uniform CompensationGatherParams {
    uint level;
    uint vpl_begin;  // shade VPL slots [vpl_begin, vpl_end)
    uint vpl_end;
    float g_clamp;   // 0: unclamped
    float weight;    // multiplies every VPL's contribution (bir's share of a batch)
} params;

layout(set = 0, binding = 14, std430) readonly buffer CompensationIn { CompensationVertex vertices[]; };

#define CHUNK 64u
shared Vpl chunk[CHUNK];
shared Material chunk_materials[CHUNK];  // vpl_material of each

void main() {
    uint count = counts[params.level];
    // Uniform over the workgroup: no invocation is left out of the barriers below.
    if (gl_WorkGroupID.x * CHUNK >= count) return;
    uint i = gl_GlobalInvocationID.x;
    bool live = i < count;
    CompensationVertex v = vertices[live ? i : 0u];
    vec3 y = v.position.xyz;
    vec3 n = v.normal.xyz;
    vec3 side = v.side.xyz;
    vec3 wo = v.wo.xyz;
    vec3 origin = offset_origin(y, side);
    uint mat = live ? floatBitsToUint(v.normal.w) : 0u;
    Material m = textured(materials[mat], mat, live ? floatBitsToUint(v.side.w) : 0u, y);

    vec3 sum = vec3(0.0);
    for (uint base = params.vpl_begin; base < params.vpl_end; base += CHUNK) {
        uint slot = base + gl_LocalInvocationIndex;
        if (slot < params.vpl_end) {
            Vpl vpl = vpls[slot];
            chunk[gl_LocalInvocationIndex] = vpl;
            chunk_materials[gl_LocalInvocationIndex] = vpl_material(vpl);
        } else {
            chunk[gl_LocalInvocationIndex].position = vec4(0.0, 0.0, 0.0, uintBitsToFloat(VPL_NONE));
            chunk_materials[gl_LocalInvocationIndex] = materials[0];
        }
        memoryBarrierShared();
        barrier();
        if (live) {
            for (uint j = 0u; j < CHUNK; ++j) {
                sum += shade_from_vpl(chunk[j], chunk_materials[j], y, origin, n, side, wo, m,
                                      params.g_clamp);
            }
        }
        barrier();
    }
    if (!live) return;
    accumulate_radiance(floatBitsToUint(v.position.w), v.beta.rgb * sum * params.weight);
}
