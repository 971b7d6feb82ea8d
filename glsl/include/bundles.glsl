// Real-time bidirectional path tracing (Tokuyoshi 12): what its kernels share. Per iteration k
// (k counts iterations over all frames; the per-frame index i = k mod I picks the light
// vertex): one light vertex (trace_light_vertices.comp: a light chosen by power, x0 on it, x1
// hit by a ray leaving it with the emission pdf) and one global ray bundle: a direction w_k
// uniform on the sphere, along which every G-buffer point x3 casts one ray, toward +w_k or
// -w_k, whichever side of its surface it lies on (Section 3.3), so that each point's
// direction has the hemisphere density p_r = 1 / (2 pi). Quasi-random numbers: scrambled
// Halton point k, dimension 0 picks the light, 1-2 the emission direction, 3-4 the bundle
// direction. Bindings 13 (LightVertices) and 14 (BundleHits); a kernel that uses only one
// defines BUNDLES_NO_HITS or BUNDLES_NO_LIGHT_VERTICES.
#ifndef BUNDLES_GLSL
#define BUNDLES_GLSL

struct LightVertex {
    vec4 light;     // x0; w: index into lights[] (uint bits)
    vec4 power;     // rgb: I(w01) / (P_l p_e(w01)); w: P_l, the light's selection probability
    vec4 position;  // x1; w: 1 when the ray from x0 hit a surface, else 0
    vec4 normal;    // shading normal at x1 on x0's side; w: material (uint bits)
    vec4 side;      // geometric normal at x1 on x0's side; w: p_e(w01) |cos| / d01^2, the area
                    // density of x1 (without P_l)
};

// The first hit of one point's bundle ray; t < 0: none (missed, or no G-buffer surface).
struct BundleHit {
    vec4 position;     // x2; w: t, the distance from x3
    uvec4 triangle;    // x: GPU triangle; yz: barycentrics (float bits)
};

#ifdef BUNDLES_WRITE_LIGHT_VERTICES
layout(set = 0, binding = 13, std430) writeonly buffer LightVertices { LightVertex light_vertices[]; };
#elif !defined(BUNDLES_NO_LIGHT_VERTICES)
layout(set = 0, binding = 13, std430) readonly buffer LightVertices { LightVertex light_vertices[]; };
#endif

#ifdef BUNDLES_WRITE_HITS
layout(set = 0, binding = 14, std430) writeonly buffer BundleHits { BundleHit bundle_hits[]; };
#elif !defined(BUNDLES_NO_HITS)
layout(set = 0, binding = 14, std430) readonly buffer BundleHits { BundleHit bundle_hits[]; };
#endif

float bundle_number(uint dimension, uint iteration, uint seed) {
    return halton(dimension, iteration, seed);
}

// w_k, uniform on the sphere.
vec3 bundle_direction(uint iteration, uint seed) {
    float z = 1.0 - 2.0 * bundle_number(3u, iteration, seed);
    float s = sqrt(max(0.0, 1.0 - z * z));
    float phi = 2.0 * PI * bundle_number(4u, iteration, seed);
    return vec3(s * cos(phi), s * sin(phi), z);
}

// The direction a point whose surface faces `side` casts along: w or -w.
vec3 bundle_ray(vec3 w, vec3 side) {
    return dot(side, w) >= 0.0 ? w : -w;
}

#endif
