#version 450
// The BSDF and cosine samplers on their own, for their tests (tests/env.rs) (bsdf.glsl, sampling.glsl): for
// one material, shading normal and outgoing direction, draw k writes bsdf_sample's direction
// and bsdf_pdf there; cosine draw k a cosine-weighted direction about n and its pdf; probe k a
// uniformly distributed direction and bsdf_pdf there (its mean times 4 pi is the pdf's
// integral over the sphere). One invocation per k.

#extension GL_GOOGLE_include_directive : require

layout(local_size_x = 64, local_size_y = 1, local_size_z = 1) in;

// bvh.glsl only because the scene bindings come as one set (GpuScene::bindings).
#include "bvh.glsl"
#include "scene.glsl"
#include "sampling.glsl"
#include "bsdf.glsl"

layout(set = 0, binding = 27, std430) writeonly buffer BsdfDraws { vec4 draws[]; };
layout(set = 0, binding = 28, std430) writeonly buffer CosineDraws { vec4 cosine_draws[]; };
layout(set = 0, binding = 29, std430) writeonly buffer BsdfProbes { vec4 probes[]; };

layout(push_constant) uniform DrawParams {
    vec4 kd;  // w: probability of the Phong lobe
    vec4 ks;  // w: Phong exponent
    vec4 n;
    vec4 wo;
    uint count;
    uint seed;
} params;

void main() {
    uint k = gl_GlobalInvocationID.x;
    if (k >= params.count) return;
    Material m;
    m.kd = params.kd;
    m.ks = params.ks;
    m.ke = vec4(0.0);
    vec3 n = normalize(params.n.xyz);
    vec3 wo = normalize(params.wo.xyz);
    vec3 u = vec3(random(params.seed, k, 0u, 0u), random(params.seed, k, 0u, 1u),
                  random(params.seed, k, 0u, 2u));
    vec3 wi;
    draws[k] = bsdf_sample(m, n, wo, u, wi) ? vec4(wi, bsdf_pdf(m, n, wo, wi)) : vec4(0.0);
    vec3 c = to_world(sample_cosine_hemisphere(u.yz), n);
    cosine_draws[k] = vec4(c, max(dot(c, n), 0.0) * INV_PI);
    float y = 1.0 - 2.0 * random(params.seed, k, 1u, 0u);
    float phi = 2.0 * PI * random(params.seed, k, 1u, 1u);
    float radius = sqrt(max(0.0, 1.0 - y * y));
    vec3 probe = vec3(radius * cos(phi), y, radius * sin(phi));
    probes[k] = vec4(probe, bsdf_pdf(m, n, wo, probe));
}
