#version 450
// The `hierarchical` sampler on its own, for its tests (env_pyramid.glsl): draw
// k writes the direction drawn from random numbers (seed, k) and the density the draw
// reports; probe k writes a uniformly distributed direction and pyramid_density there (its
// mean times 4 pi is the density's integral over the sphere). One invocation per k.

#extension GL_GOOGLE_include_directive : require

layout(local_size_x = 64, local_size_y = 1, local_size_z = 1) in;

#include "bvh.glsl"
#include "scene.glsl"
#include "sampling.glsl"
#include "env_pyramid.glsl"

layout(set = 0, binding = 27, std430) writeonly buffer PyramidDraws { vec4 draws[]; };
layout(set = 0, binding = 28, std430) writeonly buffer PyramidProbes { vec4 probes[]; };

layout(push_constant) uniform DrawParams {
    uint count;
    uint seed;
} params;

void main() {
    uint k = gl_GlobalInvocationID.x;
    if (k >= params.count) return;
    vec4 u = vec4(random(params.seed, k, 0u, 0u), random(params.seed, k, 0u, 1u),
                  random(params.seed, k, 0u, 2u), random(params.seed, k, 0u, 3u));
    vec3 d;
    float density;
    if (!pyramid_sample(u, d, density)) density = 0.0;
    draws[k] = vec4(d, density);
    float y = 1.0 - 2.0 * random(params.seed, k, 1u, 0u);
    float phi = 2.0 * PI * random(params.seed, k, 1u, 1u);
    float radius = sqrt(max(0.0, 1.0 - y * y));
    vec3 probe = vec3(radius * cos(phi), y, radius * sin(phi));
    probes[k] = vec4(probe, pyramid_density(probe));
}
