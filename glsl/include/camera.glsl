// Camera rays (src/scene/mod.rs `Camera` documents the mapping) with Keller 97 Section 4.1
// jittered low-discrepancy pixel sampling: frame f of F uses Halton point f in bases 2 and 3,
// jittered within its cell per pixel, so each pixel's F subpixel positions are stratified.
#ifndef CAMERA_GLSL
#define CAMERA_GLSL

#include "sampling.glsl"
#include "scene.glsl"

// Dimensions 0 and 1 of the (seed, pixel, frame) stream are the subpixel jitter.
vec2 subpixel_position(uint seed, uint pixel, uint frame, uint frame_count) {
    float xi0 = random(seed, pixel, frame, 0u);
    float xi1 = random(seed, pixel, frame, 1u);
    return vec2(jittered_halton(2u, frame, frame_count, xi0),
                jittered_halton(3u, frame, frame_count, xi1));
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
