// Next-event estimation: pick one light from LightEntries in proportion to its power (CPU
// table, src/scene/gpu.rs; light_bvh.glsl picks it through the light BVH instead), then
// sample it: a uniform point on an emissive triangle (area
// pdf converted to solid angle, pbrt-v4 Section 4.3 / 12.2), the delta direction of a point
// or spot light, or a direction from the environment map. The pdfs of the non-delta lights
// are also what MIS needs when a BSDF-sampled ray hits them (light_pdf_triangle, envmap).
#ifndef LIGHTS_GLSL
#define LIGHTS_GLSL

#include "sampling.glsl"
#include "scene.glsl"
#include "envmap.glsl"

struct LightSample {
    vec3 direction;  // unit, from the shading point toward the light
    float distance;  // to the light point; infinity for the environment
    vec3 radiance;   // Le (area, environment) or I * falloff / d^2 (delta lights)
    float pdf;       // selection probability times the solid-angle pdf (delta: selection only)
    bool delta;
    uint entry;      // the light's entry in LightEntries (set by sample_light_among and
                     // sample_light_bvh)
    float to_area;   // cos_light / distance^2 on an emissive triangle (a solid-angle density
                     // times it is the density over the light's area), 1 for other lights
};

// The entry among the first `count` whose range holds r (r below the count-th's lower bound).
uint select_light_among(uint r, uint count) {
    uint lo = 0u;
    uint hi = count - 1u;
    // A guarded do-while (bvh.glsl's triangle loop says why).
    if (lo < hi) {
        do {
            uint mid = (lo + hi) / 2u;
            if (r < light_entries[mid].upper) hi = mid; else lo = mid + 1u;
        } while (lo < hi);
    }
    return lo;
}

uint select_light(uint r) {
    return select_light_among(r, scene.size.z);
}

// pbrt-v4 SpotLight::I: smoothstep from cos(falloff) to cos(cone).
float spot_falloff(Light l, vec3 from_light) {
    float cos_theta = dot(from_light, l.direction.xyz);
    float edge0 = l.direction.w;
    float edge1 = l.cone.x;
    if (edge1 <= edge0) return cos_theta >= edge1 ? 1.0 : 0.0;
    return smoothstep(edge0, edge1, cos_theta);
}

// Samples entry e of the light table, chosen with `probability`, for shading point p; false
// when the sample carries nothing (a triangle seen from behind, zero pdf). r_texel picks the
// environment's texel, u places the point on the light.
bool sample_light_entry(LightEntry e, float probability, vec3 p, uint r_texel, vec2 u,
                        out LightSample s) {
    s.delta = false;
    s.radiance = vec3(0.0);
    s.pdf = 0.0;
    s.distance = 0.0;
    s.direction = vec3(0.0, 1.0, 0.0);
    s.to_area = 1.0;
    if (e.kind == 0u) {
        EmitterTriangle t = emitter_triangles[e.index];
        vec2 b = sample_uniform_triangle(u);
        vec3 q = t.p0.xyz + b.x * t.e1.xyz + b.y * t.e2.xyz;
        vec3 d = q - p;
        float dist2 = dot(d, d);
        if (dist2 <= 0.0) return false;
        float dist = sqrt(dist2);
        s.direction = d / dist;
        s.distance = dist;
        float cos_light = -dot(s.direction, t.normal.xyz);
        if (cos_light <= 0.0) return false;
        uint m = floatBitsToUint(t.normal.w);
        s.radiance = materials[m].ke.rgb;
        s.pdf = probability * dist2 / (cos_light * t.e2.w);
        s.to_area = cos_light / dist2;
        return s.pdf > 0.0;
    }
    if (SCENE_HAS_ENVIRONMENT && e.kind == 3u) {
        s.direction = env_sample(r_texel, u, s.radiance, s.pdf);
        s.pdf *= probability;
        s.distance = infinity();
        return s.pdf > 0.0;
    }
    // (Not `!SCENE_HAS_DELTA_LIGHTS`: an operation on a specialization constant is an
    // OpSpecConstantOp, which naga's reflection rejects.)
    if (SCENE_HAS_DELTA_LIGHTS) {
        Light l = lights[e.index];
        vec3 d = l.position.xyz - p;
        float dist2 = dot(d, d);
        if (dist2 <= 0.0) return false;
        s.distance = sqrt(dist2);
        s.direction = d / s.distance;
        float falloff = e.kind == 2u ? spot_falloff(l, -s.direction) : 1.0;
        s.radiance = l.intensity.rgb * (falloff / dist2);
        s.pdf = probability;
        s.delta = true;
        return falloff > 0.0;
    }
    return false;
}

// Samples a light for shading point p by the power table; false when the sample carries
// nothing. The 31-bit integer r_select picks the light, r_texel the environment's texel, u
// places the point on the chosen light; all independent. sample_light_among draws from the
// first `count` entries only, r_select below the upper bound of the last of them, whose share
// of the table is `mass` (the pdfs are divided by it).
bool sample_light_among(vec3 p, uint r_select, uint count, float mass, uint r_texel, vec2 u,
                        out LightSample s) {
    s.delta = false;
    s.radiance = vec3(0.0);
    s.pdf = 0.0;
    s.distance = 0.0;
    s.direction = vec3(0.0, 1.0, 0.0);
    s.entry = 0u;
    if (count == 0u || !(mass > 0.0)) return false;
    uint entry = select_light_among(r_select, count);
    LightEntry e = light_entries[entry];
    bool found = sample_light_entry(e, e.probability / mass, p, r_texel, u, s);
    s.entry = entry;
    return found;
}

bool sample_light(vec3 p, uint r_select, uint r_texel, vec2 u, out LightSample s) {
    return sample_light_among(p, r_select, scene.size.z, 1.0, r_texel, u, s);
}

// Solid-angle pdf of the point hit at distance t along unit direction d on triangle st, chosen
// with `probability` (the power table's, or the light BVH's), from the emitting side.
float light_pdf_triangle_chosen(ShadingTriangle st, vec3 d, float t, float probability) {
    float cos_light = -dot(d, st.geometric_normal.xyz);
    if (cos_light <= 0.0) return 0.0;
    return probability * t * t / (cos_light * st.n2.w);
}

// Solid-angle pdf with which sample_light picks the point hit at distance t along unit
// direction d on triangle st (loaded once per hit by the caller: on lavapipe every
// storage-buffer load is a loop over the lanes), from the emitting side.
float light_pdf_shading_triangle(ShadingTriangle st, vec3 d, float t) {
    return light_pdf_triangle_chosen(st, d, t, st.n1.w);
}

// The same for GPU triangle `triangle`.
float light_pdf_triangle(uint triangle, vec3 d, float t) {
    return light_pdf_shading_triangle(shading_triangles[triangle], d, t);
}

float light_pdf_environment(vec3 d) {
    return scene.env.x * env_pdf(d);
}

#endif
