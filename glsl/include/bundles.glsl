// Real-time bidirectional path tracing (Tokuyoshi 12): what its kernels share. Per iteration k
// (k counts iterations over all frames; i = k mod I is the frame's iteration), with S light
// vertices per iteration (one per point or spot light, or 1 under Russian roulette) at
// LightVertices[i * S + s], trace_light_vertices.comp writes once: each light vertex (x0 on its
// light, x1 hit by a ray leaving it with the emission pdf) and the global ray bundle's
// direction w_k, drawn from bundle_directions.glsl's density, along which every G-buffer point
// x3 casts one ray, toward +w_k or -w_k, whichever side of its surface it lies on (Section
// 3.3): the ray's direction then has the hemisphere density p_r (1 / (2 pi) for uniform w_k).
// Quasi-random numbers: scrambled Halton point k, dimension 0 picks the light (roulette), 1-2
// the emission direction, 3-6 the bundle direction. Bindings 13 (LightVertices) and 14
// (BundleHits; a kernel that does not use them defines BUNDLES_NO_HITS).
#ifndef BUNDLES_GLSL
#define BUNDLES_GLSL

struct LightVertex {
    vec4 light;     // x0; w: index into lights[] (uint bits)
    vec4 power;     // rgb: I(w01) / (P_l p_e(w01)); w: P_l, the light's selection probability
                    // (1 when every light has a vertex; 0: no light, the slot holds w_k only)
    vec4 position;  // x1; w: 1 when the ray from x0 hit a surface, else 0
    vec4 normal;    // shading normal at x1 on x0's side; w: x1's GPU triangle (uint bits)
    vec4 side;      // geometric normal at x1 on x0's side; w: p_e(w01) |cos| / d01^2, the area
                    // density of x1 (without P_l)
    vec4 bundle;    // w_k, the iteration's bundle direction; w: p_r(w_k) = p_r(-w_k)
};

// The first hit of one point's bundle ray; t < 0: none (missed, or no G-buffer surface).
struct BundleHit {
    vec4 position;     // x2; w: t, the distance from x3
    uvec4 triangle;    // x: GPU triangle; yz: barycentrics (float bits)
};

#ifdef BUNDLES_WRITE_LIGHT_VERTICES
layout(set = 0, binding = 13, std430) writeonly buffer LightVertices { LightVertex light_vertices[]; };
#else
layout(set = 0, binding = 13, std430) readonly buffer LightVertices { LightVertex light_vertices[]; };
#endif

#ifdef BUNDLES_WRITE_HITS
layout(set = 0, binding = 14, std430) writeonly buffer BundleHits { BundleHit bundle_hits[]; };
#elif !defined(BUNDLES_NO_HITS)
layout(set = 0, binding = 14, std430) readonly buffer BundleHits { BundleHit bundle_hits[]; };
#endif

// The direction a point whose surface faces `side` casts along: w or -w.
vec3 bundle_ray(vec3 w, vec3 side) {
    return dot(side, w) >= 0.0 ? w : -w;
}

#endif
