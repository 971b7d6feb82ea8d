// The G-buffer every method shades from (glsl/write_gbuffer.comp writes it once per frame):
// the first hit of each pixel's camera ray. Binding 10.
#ifndef GBUFFER_GLSL
#define GBUFFER_GLSL

struct GBufferTexel {
    vec4 position;         // hit point; w: hit distance, negative when the ray missed
    vec4 shading_normal;   // unit, interpolated, as stored (not flipped); w: material (uint bits)
    vec4 geometric_normal; // unit, counter-clockwise side; w: GPU triangle index (uint bits)
    vec4 direction;        // unit camera ray direction; w: unused
};

#ifdef GBUFFER_WRITE
layout(set = 0, binding = 10, std430) writeonly buffer GBuffer { GBufferTexel gbuffer[]; };
#else
layout(set = 0, binding = 10, std430) readonly buffer GBuffer { GBufferTexel gbuffer[]; };
#endif

#endif
