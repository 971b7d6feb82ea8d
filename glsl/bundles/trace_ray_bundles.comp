#version 450
// Tokuyoshi 12 Section 3.2: global ray bundles, traced through the BVH instead of rasterized
// into per-pixel linked lists. For each iteration of the chunk (the z of the dispatch) every
// G-buffer point x3 casts one ray along the iteration's shared direction, +w_k or -w_k on its
// side (bundles.glsl), and records the first hit x2 for shade_bundle_paths.comp.

#extension GL_GOOGLE_include_directive : require

layout(local_size_x = 8, local_size_y = 8, local_size_z = 1) in;

#define BUNDLES_WRITE_HITS
#include "bvh.glsl"
#include "scene.glsl"
#include "sampling.glsl"
#include "gbuffer.glsl"
#include "bundles.glsl"

layout(push_constant) uniform BundleParams {
    uint first_index;  // the chunk's first iteration of the frame
    uint slots;        // light vertices per iteration
} params;

void main() {
    uvec2 pixel = gl_GlobalInvocationID.xy;
    if (pixel.x >= scene.size.x || pixel.y >= scene.size.y) return;
    uint index = pixel.y * scene.size.x + pixel.x;
    uint pixels = scene.size.x * scene.size.y;
    uint slot = gl_GlobalInvocationID.z * pixels + index;

    BundleHit h;
    h.position = vec4(0.0, 0.0, 0.0, -1.0);
    h.triangle = uvec4(0u);
    GBufferTexel g = gbuffer[index];
    vec3 wo, side, n;
    if (gbuffer_surface(g, wo, side, n)) {
        vec3 w = light_vertices[(params.first_index + gl_GlobalInvocationID.z) * params.slots].bundle.xyz;
        vec3 d = bundle_ray(w, side);
        vec3 origin = offset_origin(g.position.xyz, side);
        RayHit hit;
        if (trace_closest(origin, d, infinity(), hit)) {
            h.position = vec4(origin + hit.t * d, hit.t);
            h.triangle = uvec4(hit.triangle, floatBitsToUint(hit.barycentrics.x),
                               floatBitsToUint(hit.barycentrics.y), 0u);
        }
    }
    bundle_hits[slot] = h;
}
