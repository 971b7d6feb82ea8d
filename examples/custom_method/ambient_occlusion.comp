#version 450
// Ambient occlusion, the kernel of examples/custom_method.rs (a method defined outside irad):
// per pixel and frame, at the G-buffer's hit, `rays` cosine-weighted directions about the
// shading side's geometric normal, each traced without a distance limit; the estimate is the
// fraction that escape, (1/N) sum V(w), whose mean is the cosine-weighted unoccluded fraction
// (1 on an open plane; 1/2 anywhere on an infinite floor meeting an infinite wall). A pixel
// whose camera ray missed adds 0.
//
// Random dimensions per (seed, pixel, frame): ray k at 2k and 2k + 1.
// Compiled like irad's own kernels, from the repository root:
//   glslangValidator -V --target-env vulkan1.1 -Iglsl/include
//     -o examples/custom_method/ambient_occlusion.spv examples/custom_method/ambient_occlusion.comp
// (one line); the example checks that the committed module is this file's when glslang is
// installed.

#extension GL_GOOGLE_include_directive : require

layout(local_size_x = 8, local_size_y = 8, local_size_z = 1) in;

#include "bvh.glsl"
#include "scene.glsl"
#include "sampling.glsl"
#include "gbuffer.glsl"
#include "radiance.glsl"

layout(push_constant) uniform AoParams {
    uint frame;
    uint seed;
    uint rays;
} params;

void main() {
    uvec2 pixel = gl_GlobalInvocationID.xy;
    if (pixel.x >= scene.size.x || pixel.y >= scene.size.y) return;
    uint index = pixel.y * scene.size.x + pixel.x;
    GBufferTexel g = gbuffer[index];
    vec3 wo, side, n;
    if (!gbuffer_surface(g, wo, side, n)) {
        accumulate_radiance(index, vec3(0.0));
        return;
    }
    vec3 origin = offset_origin(g.position.xyz, side);
    float open = 0.0;
    for (uint k = 0u; k < params.rays; ++k) {
        vec2 u = vec2(random(params.seed, index, params.frame, 2u * k),
                      random(params.seed, index, params.frame, 2u * k + 1u));
        vec3 w = to_world(sample_cosine_hemisphere(u), side);
        if (!trace_any(origin, w, infinity())) open += 1.0;
    }
    accumulate_radiance(index, vec3(open / float(max(params.rays, 1u))));
}
