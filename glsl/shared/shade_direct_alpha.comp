#version 450
// The reference's direct light (one scattering event, --max-depth 1) with Lu 14 Chapter 5's
// per-pixel split between light sampling and BSDF sampling, for area lights and the
// environment alike (delta lights are reached by light samples only, weight 1). Per pixel and
// frame, at the G-buffer point: the emission the camera sees, then c_L light samples (one
// light chosen by power, lights.glsl) and c_B BSDF samples (each traced to the emitter or the
// map it reaches), the last of each weighted by its fraction, every one weighted by the
// balance heuristic over the counts, f / (c_L p_L + c_B p_B) (Veach's multi-sample form).
// Frames 0 .. M-1 take c_L = c_B = 1 (the balance heuristic's half and half) and add Eq. 5.5's
// two sums to the pixel's DirectAlphaState from the luminance of f (visibility included);
// frames from M on take c_B = 2 alpha and c_L = 2 (1 - alpha), alpha = (2 + I_1 / I_2) / 4
// (Eq. 5.4, the BSDF share) clamped to [0.025, 0.975], fixed after frame M - 1 so it never
// weighs the samples it came from. The accumulation's plain mean over frames is Eq. 5.6.
//
// Random dimensions per (seed, pixel, frame): light sample k at 2 + 8k (selection +0, texel
// +1, point +2, +3), BSDF sample k at 34 + 8k (+0 .. +2).

#extension GL_GOOGLE_include_directive : require

layout(local_size_x = 8, local_size_y = 8, local_size_z = 1) in;

#include "bvh.glsl"
#include "scene.glsl"
#include "sampling.glsl"
#include "bsdf.glsl"
#include "lights.glsl"
#include "gbuffer.glsl"
#include "radiance.glsl"

// Per pixel: x, y Eq. 5.5's sums over the estimation frames; z the later frames that saw a
// surface here, w their alphas summed.
layout(set = 0, binding = 26, std430) buffer DirectAlphaState { vec4 alpha_state[]; };

layout(push_constant) uniform AlphaParams {
    uint frame;
    uint seed;
    uint estimation_frames;  // M
} params;

// Lu 14 Section 5.4.3.
#define ALPHA_MIN 0.025
#define ALPHA_MAX 0.975

// Eq. 5.5's terms for one sample of the half-and-half mixture with contribution f (luminance)
// and densities p_l, p_b: x = f / p_mean, (x^2 dp / p_mean, x^2 dp^2 / p_mean^2).
vec2 alpha_terms(float f, float p_l, float p_b) {
    float mean = 0.5 * (p_b + p_l);
    float delta = 0.5 * (p_b - p_l);
    if (!(mean > 0.0) || !(f > 0.0)) return vec2(0.0);
    float x = f / mean;
    float r = delta / mean;
    return x * x * vec2(r, r * r);
}

void main() {
    uvec2 pixel = gl_GlobalInvocationID.xy;
    if (pixel.x >= scene.size.x || pixel.y >= scene.size.y) return;
    uint index = pixel.y * scene.size.x + pixel.x;
    GBufferTexel g = gbuffer[index];
    vec3 dir = g.direction.xyz;
    vec3 L = vec3(0.0);
    vec3 wo, side, n;
    if (!gbuffer_surface(g, wo, side, n)) {
        accumulate_radiance(index, env_radiance(dir));
        return;
    }
    Material m = gbuffer_material(g);
    vec3 ng = g.geometric_normal.xyz;
    if (m.ke.w > 0.0 && dot(wo, ng) > 0.0) L += m.ke.rgb;
    vec3 p = g.position.xyz;
    vec3 origin = offset_origin(p, side);

    bool estimating = params.frame < params.estimation_frames;
    vec4 state = alpha_state[index];
    float alpha = 0.5;
    if (!estimating && state.y > 0.0) {
        alpha = clamp(0.25 * (2.0 + state.x / state.y), ALPHA_MIN, ALPHA_MAX);
    }
    float c_l = 2.0 * (1.0 - alpha);
    float c_b = 2.0 * alpha;
    vec2 terms = vec2(0.0);

    for (uint k = 0u; k < uint(ceil(c_l)); ++k) {
        float beta = min(1.0, c_l - float(k));
        uint dim = 2u + 8u * k;
        LightSample ls;
        uint r_select = random_u31(params.seed, index, params.frame, dim);
        uint r_texel = random_u31(params.seed, index, params.frame, dim + 1u);
        vec2 u = vec2(random(params.seed, index, params.frame, dim + 2u),
                      random(params.seed, index, params.frame, dim + 3u));
        if (!sample_light(p, r_select, r_texel, u, ls)) continue;
        float cos_i = dot(ls.direction, n);
        if (cos_i <= 0.0 || dot(ls.direction, side) <= 0.0) continue;
        vec3 f = bsdf_eval(m, n, wo, ls.direction) * cos_i * ls.radiance;
        if (!(max(max(f.r, f.g), f.b) > 0.0)) continue;
        bool visible;
        if (isinf(ls.distance)) {
            visible = !trace_any(origin, ls.direction, infinity());
        } else {
            vec3 to_light = p + ls.direction * ls.distance - origin;
            visible = !trace_any(origin, to_light, 0.9999);
        }
        if (!visible) continue;
        if (ls.delta) {
            L += beta * f / (c_l * ls.pdf);
            continue;
        }
        float p_b = bsdf_pdf(m, n, wo, ls.direction);
        L += beta * f / (c_l * ls.pdf + c_b * p_b);
        if (estimating) terms += alpha_terms(luminance(f), ls.pdf, p_b);
    }

    for (uint k = 0u; k < uint(ceil(c_b)); ++k) {
        float beta = min(1.0, c_b - float(k));
        uint dim = 34u + 8u * k;
        vec3 u = vec3(random(params.seed, index, params.frame, dim),
                      random(params.seed, index, params.frame, dim + 1u),
                      random(params.seed, index, params.frame, dim + 2u));
        vec3 wi;
        if (!bsdf_sample(m, n, wo, u, wi)) continue;
        float p_b = bsdf_pdf(m, n, wo, wi);
        float cos_i = dot(wi, n);
        if (!(p_b > 0.0) || cos_i <= 0.0 || dot(wi, side) <= 0.0) continue;
        RayHit hit;
        vec3 le;
        float p_l;
        if (trace_closest(origin, wi, infinity(), hit)) {
            uint tri = hit.triangle;
            Material hm = materials[triangle_material(tri)];
            if (!(hm.ke.w > 0.0) || dot(-wi, shading_triangles[tri].geometric_normal.xyz) <= 0.0) {
                continue;
            }
            le = hm.ke.rgb;
            p_l = light_pdf_triangle(tri, wi, hit.t);
        } else {
            le = env_radiance(wi);
            p_l = light_pdf_environment(wi);
        }
        vec3 f = bsdf_eval(m, n, wo, wi) * cos_i * le;
        if (!(max(max(f.r, f.g), f.b) > 0.0)) continue;
        L += beta * f / (c_l * p_l + c_b * p_b);
        if (estimating) terms += alpha_terms(luminance(f), p_l, p_b);
    }

    if (estimating) {
        alpha_state[index].xy = state.xy + terms;
    } else {
        alpha_state[index].zw = state.zw + vec2(1.0, alpha);
    }
    accumulate_radiance(index, L);
}
