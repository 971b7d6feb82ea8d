// The G-buffer every method shades from (glsl/shared/write_gbuffer.comp writes it once per frame):
// the first hit of each pixel's camera ray. Binding 10.
#ifndef GBUFFER_GLSL
#define GBUFFER_GLSL

#include "scene.glsl"

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

// The surface of a texel as the shading side sees it: wo toward the camera, the geometric
// normal `side` and the shading normal `n` both flipped onto wo's side. False when the camera
// ray missed.
bool gbuffer_surface(GBufferTexel g, out vec3 wo, out vec3 side, out vec3 n) {
    wo = -g.direction.xyz;
    vec3 ng = g.geometric_normal.xyz;
    side = dot(wo, ng) >= 0.0 ? ng : -ng;
    vec3 ns = g.shading_normal.xyz;
    n = dot(ns, side) >= 0.0 ? ns : -ns;
    return g.position.w >= 0.0;
}

// The texel's material, textured at its point (material 0 where the camera ray missed).
Material gbuffer_material(GBufferTexel g) {
    bool hit = g.position.w >= 0.0;
    uint material = hit ? floatBitsToUint(g.shading_normal.w) : 0u;
    uint triangle = hit ? floatBitsToUint(g.geometric_normal.w) : 0u;
    return textured(materials[material], material, triangle, g.position.xyz);
}

#endif
