// The one BSDF irad models (docs/DESIGN.md "Conventions"): Lambert plus a normalized modified
// Phong lobe (Lafortune and Willems 1994), f = Kd / pi + Ks (n + 2) / (2 pi) cos^n(alpha),
// alpha between wi and the mirror direction of wo. Sampled as a mixture: the cosine lobe with
// probability 1 - p, the Phong lobe (pdf (n + 1) / (2 pi) cos^n(alpha)) with probability p,
// p = Y(Ks) / (Y(Kd) + Y(Ks)) (Material.kd.w); the pdf is the mixture's, so both lobes are
// combined by one-sample MIS (balance heuristic).
// All directions are unit and point away from the surface; n is the shading normal on the
// side of wo.
#ifndef BSDF_GLSL
#define BSDF_GLSL

#include "sampling.glsl"
#include "scene.glsl"

vec3 phong_mirror(vec3 wo, vec3 n) {
    return 2.0 * dot(wo, n) * n - wo;
}

// f(wo, wi), zero when either direction is below the surface.
vec3 bsdf_eval(Material m, vec3 n, vec3 wo, vec3 wi) {
    if (dot(wi, n) <= 0.0 || dot(wo, n) <= 0.0) return vec3(0.0);
    vec3 f = m.kd.rgb * INV_PI;
    float exponent = m.ks.w;
    float c = dot(phong_mirror(wo, n), wi);
    if (SCENE_HAS_GLOSSY && c > 0.0 && max(max(m.ks.r, m.ks.g), m.ks.b) > 0.0) {
        f += m.ks.rgb * ((exponent + 2.0) * (0.5 * INV_PI) * pow(c, exponent));
    }
    return f;
}

// The mixture pdf (solid angle) of sampling wi.
float bsdf_pdf(Material m, vec3 n, vec3 wo, vec3 wi) {
    float cos_theta = dot(wi, n);
    if (dot(wo, n) <= 0.0) return 0.0;
    float p_spec = m.kd.w;
    float pdf = cos_theta > 0.0 ? (1.0 - p_spec) * cos_theta * INV_PI : 0.0;
    float c = dot(phong_mirror(wo, n), wi);
    if (SCENE_HAS_GLOSSY && c > 0.0 && p_spec > 0.0) {
        float exponent = m.ks.w;
        pdf += p_spec * (exponent + 1.0) * (0.5 * INV_PI) * pow(c, exponent);
    }
    return pdf;
}

// Samples wi from the mixture; returns false when the material reflects nothing.
// u.x picks the lobe, u.yz warp within it.
bool bsdf_sample(Material m, vec3 n, vec3 wo, vec3 u, out vec3 wi) {
    float p_spec = m.kd.w;
    if (max(max(m.kd.r, m.kd.g), m.kd.b) <= 0.0 && p_spec <= 0.0) return false;
    if (SCENE_HAS_GLOSSY && u.x < p_spec) {
        float exponent = m.ks.w;
        float cos_alpha = pow(u.y, 1.0 / (exponent + 1.0));
        float sin_alpha = sqrt(max(0.0, 1.0 - cos_alpha * cos_alpha));
        float phi = 2.0 * PI * u.z;
        wi = to_world(vec3(sin_alpha * cos(phi), sin_alpha * sin(phi), cos_alpha),
                      phong_mirror(wo, n));
    } else {
        wi = to_world(sample_cosine_hemisphere(u.yz), n);
    }
    return true;
}

#endif
