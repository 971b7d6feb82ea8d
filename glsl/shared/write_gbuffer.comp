#version 450
// The G-buffer pass shared by every method: one camera ray per pixel at a low-discrepancy
// subpixel position (Keller 97 Section 4.1, camera.glsl), traced to its closest hit.

#extension GL_GOOGLE_include_directive : require

layout(local_size_x = 8, local_size_y = 8, local_size_z = 1) in;

#define GBUFFER_WRITE
#include "bvh.glsl"
#include "scene.glsl"
#include "camera.glsl"
#include "gbuffer.glsl"

layout(push_constant) uniform FrameParams {
    uint frame;
    uint seed;
    uint centred;  // 1: every frame samples pixel centres (no antialiasing)
    uint _pad;
} params;

void main() {
    uvec2 pixel = gl_GlobalInvocationID.xy;
    if (pixel.x >= scene.size.x || pixel.y >= scene.size.y) return;
    uint index = pixel.y * scene.size.x + pixel.x;
    vec2 subpixel = params.centred != 0u ? vec2(0.5)
                                         : subpixel_position(params.seed, index, params.frame);
    vec3 direction = camera_direction(pixel, subpixel);
    vec3 origin = scene.camera_position.xyz;

    GBufferTexel texel;
    texel.direction = vec4(direction, 0.0);
    RayHit hit;
    if (trace_closest(origin, direction, infinity(), hit)) {
        ShadingTriangle t = shading_triangles[hit.triangle];
        texel.position = vec4(origin + hit.t * direction, hit.t);
        texel.shading_normal = vec4(shading_normal(hit.triangle, hit.barycentrics), t.n0.w);
        texel.geometric_normal = vec4(t.geometric_normal.xyz, uintBitsToFloat(hit.triangle));
    } else {
        texel.position = vec4(origin, -1.0);
        texel.shading_normal = vec4(0.0);
        texel.geometric_normal = vec4(0.0, 0.0, 0.0, uintBitsToFloat(0xffffffffu));
    }
    gbuffer[index] = texel;
}
