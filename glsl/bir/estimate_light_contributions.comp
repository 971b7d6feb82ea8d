#version 450
// Segovia 06 Section 4.1 (after Dietrich et al.): how much each light lights what the camera
// sees, measured along camera paths, so that a CDF over these contributions (not over the
// lights' power) chooses which lights start light paths. Invocation (s, l): camera sample s (a
// G-buffer texel at a pseudo-random pixel, x1, and x2, one cosine-distributed bounce further)
// and light entry l: the luminance of l's direct light at x1, plus at x2 times Kd(x1), each
// from one point on the light and one shadow ray. Writes Contributions[l * samples + s]; the
// prefix sum's row totals are the per-light sums.
//
// Numbers: PCG keyed by (seed, s, dimension); the point on light l by (seed, s, l).

#extension GL_GOOGLE_include_directive : require

layout(local_size_x = 64, local_size_y = 1, local_size_z = 1) in;

#include "bvh.glsl"
#include "scene.glsl"
#include "sampling.glsl"
#include "bsdf.glsl"
#include "lights.glsl"
#include "gbuffer.glsl"

layout(set = 0, binding = 22, std430) writeonly buffer Contributions { float contributions[]; };

layout(push_constant) uniform ContributionParams {
    uint samples;  // camera samples (row length)
    uint entries;  // light entries (rows)
    uint seed;
    uint pixels;
} params;

// Light entry e's direct light at x (offset off the surface along side), one sample.
vec3 direct_from(LightEntry e, uint l, uint s, vec3 x, vec3 n, vec3 side, vec3 wo, Material m) {
    vec3 target;
    vec3 radiance;  // times 1 / pdf, per unit of cos at x
    vec2 u = vec2(random(params.seed, s, 0x6c636466u, 2u * l),
                  random(params.seed, s, 0x6c636466u, 2u * l + 1u));
    if (e.kind == 0u) {
        EmitterTriangle t = emitter_triangles[e.index];
        vec2 b = sample_uniform_triangle(u);
        target = t.p0.xyz + b.x * t.e1.xyz + b.y * t.e2.xyz;
        vec3 d = target - x;
        float dist2 = dot(d, d);
        if (dist2 <= 0.0) return vec3(0.0);
        vec3 w = d * inversesqrt(dist2);
        float cos_l = -dot(w, t.normal.xyz);
        if (cos_l <= 0.0) return vec3(0.0);
        // Le G / pdf_area, pdf_area = 1 / A (t.e2.w is the area).
        radiance = materials[floatBitsToUint(t.normal.w)].ke.rgb * (cos_l * t.e2.w / dist2);
    } else if (e.kind == 1u || e.kind == 2u) {
        Light light = lights[e.index];
        target = light.position.xyz;
        vec3 d = target - x;
        float dist2 = dot(d, d);
        if (dist2 <= 0.0) return vec3(0.0);
        float falloff = e.kind == 2u ? spot_falloff(light, -d * inversesqrt(dist2)) : 1.0;
        radiance = light.intensity.rgb * (falloff / dist2);
    } else {
        return vec3(0.0);  // the environment: bir declines it
    }
    vec3 w = normalize(target - x);
    float cos_x = dot(n, w);
    if (cos_x <= 0.0 || dot(side, w) <= 0.0) return vec3(0.0);
    vec3 f = bsdf_eval(m, n, wo, w);
    if (max(max(f.r, f.g), f.b) <= 0.0) return vec3(0.0);
    if (trace_any(x, target - x, 0.9999)) return vec3(0.0);
    return f * cos_x * radiance;
}

void main() {
    uint s = gl_GlobalInvocationID.x;
    uint l = gl_GlobalInvocationID.y;
    if (s >= params.samples || l >= params.entries) return;
    uint pixel = hash4(params.seed, s, 0x6c636466u, 99u) % params.pixels;
    GBufferTexel g = gbuffer[pixel];
    float value = 0.0;
    vec3 wo, side, n;
    if (gbuffer_surface(g, wo, side, n)) {
        LightEntry e = light_entries[l];
        vec3 x = offset_origin(g.position.xyz, side);
        Material m = gbuffer_material(g);
        value = luminance(direct_from(e, l, s, x, n, side, wo, m));
        // One bounce further: x2 by cosine sampling, weighted by Kd(x1).
        vec2 u = vec2(random(params.seed, s, 0x6c636466u, 0x10000u),
                      random(params.seed, s, 0x6c636466u, 0x10001u));
        vec3 w = to_world(sample_cosine_hemisphere(u), n);
        RayHit hit;
        if (dot(w, side) > 0.0 && trace_closest(x, w, infinity(), hit)) {
            vec3 ng2 = shading_triangles[hit.triangle].geometric_normal.xyz;
            vec3 side2 = dot(-w, ng2) >= 0.0 ? ng2 : -ng2;
            vec3 ns2 = shading_normal(hit.triangle, hit.barycentrics);
            vec3 n2 = dot(ns2, side2) >= 0.0 ? ns2 : -ns2;
            vec3 x2 = offset_origin(x + hit.t * w, side2);
            Material m2 = surface_material(hit.triangle, x + hit.t * w);
            value += luminance(m.kd.rgb) * luminance(direct_from(e, l, s, x2, n2, side2, -w, m2));
        }
    }
    contributions[l * params.samples + s] = (isnan(value) || isinf(value)) ? 0.0 : value;
}
