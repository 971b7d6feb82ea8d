// Camera rays (src/scene/mod.rs `Camera` documents the mapping) with Keller 97 Section 4.1
// low-discrepancy pixel sampling: frame f uses Halton point f in bases 2 and 3, shifted per
// pixel (Cranley-Patterson, sampling.glsl), so each pixel's subpixel positions are stratified
// over the whole pixel for any frame count and differ between pixels.
#ifndef CAMERA_GLSL
#define CAMERA_GLSL

#include "sampling.glsl"
#include "scene.glsl"

// The shift is dimensions 0 and 1 of the pixel's stream at sample index 0xffffffff, the same
// for every frame.
vec2 subpixel_position(uint seed, uint pixel, uint frame) {
    float xi0 = random(seed, pixel, 0xffffffffu, 0u);
    float xi1 = random(seed, pixel, 0xffffffffu, 1u);
    return vec2(shifted_halton(2u, frame, xi0), shifted_halton(3u, frame, xi1));
}

vec3 camera_direction(uvec2 pixel, vec2 subpixel) {
    float t = scene.camera_position.w;
    float aspect = scene.camera_forward.w;
    vec2 size = vec2(scene.size.xy);
    float a = (2.0 * (float(pixel.x) + subpixel.x) / size.x - 1.0) * t * aspect;
    float b = (1.0 - 2.0 * (float(pixel.y) + subpixel.y) / size.y) * t;
    return normalize(scene.camera_forward.xyz + a * scene.camera_right.xyz + b * scene.camera_up.xyz);
}

#endif
