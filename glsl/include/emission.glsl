// Emission sampling of point and spot lights by their intensity (Tokuyoshi 12 Section 4.1):
// p_e(w) = 1 / (4 pi) for a point light and I(w) / integral of I for a spot light, whose
// intensity follows pbrt-v4's smoothstep falloff (lights.glsl spot_falloff). The spot is
// sampled as pbrt-v4's SpotLight::SampleLe does: the full-intensity cone or the falloff ring by
// their share of the integral, uniform in the cone, and in the ring the smoothstep inverted
// (here by bisection of its integral t^3 - t^4 / 2). Needs sampling.glsl, scene.glsl and
// lights.glsl.
#ifndef EMISSION_GLSL
#define EMISSION_GLSL

// The integral of I / intensity over the sphere: 4 pi for a point light; for a spot
// 2 pi ((1 - cos_cone) + (cos_cone - cos_falloff) / 2).
float emission_solid_angle(Light l) {
    if (l.position.w != 2.0) return 4.0 * PI;
    float cos_falloff = l.direction.w;
    float cos_cone = max(l.cone.x, cos_falloff);
    return 2.0 * PI * ((1.0 - cos_cone) + 0.5 * (cos_cone - cos_falloff));
}

// I(w) / intensity: 1 for a point light, the falloff for a spot.
float emission_profile(Light l, vec3 w) {
    if (l.position.w != 2.0) return 1.0;
    return spot_falloff(l, w);
}

// p_e(w), solid angle.
float emission_pdf(Light l, vec3 w) {
    return emission_profile(l, w) / emission_solid_angle(l);
}

// A direction leaving light l with density emission_pdf.
vec3 sample_emission(Light l, vec2 u) {
    float cos_theta;
    vec3 axis = vec3(0.0, 0.0, 1.0);
    if (l.position.w != 2.0) {
        cos_theta = 1.0 - 2.0 * u.x;
    } else {
        axis = l.direction.xyz;
        float cos_falloff = l.direction.w;
        float cos_cone = max(l.cone.x, cos_falloff);
        float cone = 1.0 - cos_cone;
        float ring = 0.5 * (cos_cone - cos_falloff);
        float pick = u.x * (cone + ring);
        if (pick < cone || ring <= 0.0) {
            cos_theta = 1.0 - min(pick, cone);
        } else {
            // t in [0, 1] across the ring, density 2 (3 t^2 - 2 t^3): its integral
            // 2 t^3 - t^4 equals the rescaled number.
            float target = (pick - cone) / ring;
            float lo = 0.0;
            float hi = 1.0;
            for (int i = 0; i < 24; ++i) {
                float t = 0.5 * (lo + hi);
                if (2.0 * t * t * t - t * t * t * t < target) lo = t; else hi = t;
            }
            cos_theta = mix(cos_falloff, cos_cone, 0.5 * (lo + hi));
        }
    }
    float sin_theta = sqrt(max(0.0, 1.0 - cos_theta * cos_theta));
    float phi = 2.0 * PI * u.y;
    return to_world(vec3(sin_theta * cos(phi), sin_theta * sin(phi), cos_theta), axis);
}

#endif
