#version 450
// Interleaved sampling's reconstruction (Keller and Heidrich 2001; Segovia 06 Section 5's
// G-buffer splitting): each pixel of a k x k block shaded a different VPL subset; a pixel's
// estimate is restored by averaging the block's estimates over the pixels that see the same
// surface (discontinuity-aware: hit points on the pixel's tangent plane within a fraction of
// its camera distance, normals within ~25 degrees). Every subset is a random share of the
// VPLs weighted by k^2, so an average over any of them estimates the full sum; at a
// discontinuity the average takes fewer subsets (more noise), never the other surface.

#extension GL_GOOGLE_include_directive : require

layout(local_size_x = 8, local_size_y = 8, local_size_z = 1) in;

#include "scene.glsl"
#include "gbuffer.glsl"
#include "radiance.glsl"

layout(set = 0, binding = 15, std430) readonly buffer VplRadiance { vec4 vpl_radiance[]; };

layout(push_constant) uniform FilterParams {
    uint interleave;          // k
    float plane_tolerance;    // |(q - p) . n_p| / (camera distance of p)
    float normal_tolerance;   // minimum n_p . n_q
    uint _pad;
} params;

void main() {
    uvec2 pixel = gl_GlobalInvocationID.xy;
    if (pixel.x >= scene.size.x || pixel.y >= scene.size.y) return;
    uint index = pixel.y * scene.size.x + pixel.x;
    GBufferTexel g = gbuffer[index];
    if (g.position.w < 0.0) return;
    uint k = params.interleave;
    uvec2 block = pixel - pixel % k;
    vec3 p = g.position.xyz;
    vec3 n = g.shading_normal.xyz;
    float tolerance = params.plane_tolerance * g.position.w;
    vec3 sum = vec3(0.0);
    float count = 0.0;
    for (uint dy = 0u; dy < k; ++dy) {
        for (uint dx = 0u; dx < k; ++dx) {
            uvec2 q = block + uvec2(dx, dy);
            if (q.x >= scene.size.x || q.y >= scene.size.y) continue;
            uint qi = q.y * scene.size.x + q.x;
            GBufferTexel h = gbuffer[qi];
            bool same = qi == index
                || (h.position.w >= 0.0
                    && abs(dot(h.position.xyz - p, n)) <= tolerance
                    && dot(h.shading_normal.xyz, n) >= params.normal_tolerance);
            if (same) {
                sum += vpl_radiance[qi].rgb;
                count += 1.0;
            }
        }
    }
    accumulate_radiance(index, sum / count);
}
