// A placed light-field luminaire (Lu 14 Section 4.3; src/scene/luminaire/mod.rs is the model,
// src/sampling/luminaire.rs the f64 mirror): its frame, the bases Phi_m, the windows of
// Eq. 4.11 and each image's share of a point's samples (Eq. 4.14, 4.16). In the luminaire's
// frame the filter plane U is z = 0 and the image plane S is z = delta; light leaves toward
// +z. Shared by estimate_luminaire_areas.comp (Lu's step 1) and shade_lightfield.comp (step 2),
// so both compute the very same A_m. Binding 34.
#ifndef LUMINAIRE_GLSL
#define LUMINAIRE_GLSL

#include "luminaire_tables.glsl"

struct LuminaireFrame {
    vec4 position;    // the filter plane's origin
    vec4 x;           // world axes
    vec4 y;
    vec4 z;
    vec4 plane;       // (pitch u, pitch v, delta, basis reach in pitches)
    vec4 image_size;  // (sx, sy, texels per m2, 0)
    uvec4 grid;       // (W, H, R_s, R_t)
    uvec4 options;    // (basis: 0 bilinear, 1 quadratic B-spline; strategy; K; K_max)
};
layout(set = 0, binding = 34, std430) readonly buffer LuminaireParams { LuminaireFrame lf; };

#define STRATEGY_RESTRICTED 0u
#define STRATEGY_UNIFORM 1u
#define STRATEGY_PRECOMPUTED 2u
#define STRATEGY_BRUTE_FORCE 3u

uint luminaire_images() { return lf.grid.x * lf.grid.y; }

LuminaireImage luminaire_image(uint m) { return LuminaireImage(m, lf.grid.z, lf.grid.w); }

float basis_weight(float x) {
    float a = abs(x);
    if (lf.options.x == 0u) return max(1.0 - a, 0.0);
    if (a < 0.5) return 0.75 - a * a;
    if (a < 1.5) return 0.5 * (1.5 - a) * (1.5 - a);
    return 0.0;
}

// Node u_m of basis m on U.
vec2 basis_node(uint m) {
    uint i = m % lf.grid.x;
    uint j = m / lf.grid.x;
    return vec2((float(i) - 0.5 * float(lf.grid.x - 1u)) * lf.plane.x,
                (float(j) - 0.5 * float(lf.grid.y - 1u)) * lf.plane.y);
}

// Half the support box of every Phi_m, metres.
vec2 basis_half_support() { return lf.plane.w * lf.plane.xy; }

float phi(uint m, vec2 u) {
    vec2 c = basis_node(m);
    return basis_weight((u.x - c.x) / lf.plane.x) * basis_weight((u.y - c.y) / lf.plane.y);
}

vec2 plane_to_texels(vec2 s) {
    return (s / lf.image_size.xy + 0.5) * vec2(lf.grid.zw);
}

vec2 texels_to_plane(vec2 t) {
    return (t / vec2(lf.grid.zw) - 0.5) * lf.image_size.xy;
}

// A world point in the luminaire's frame.
vec3 to_luminaire(vec3 world) {
    vec3 d = world - lf.position.xyz;
    return vec3(dot(d, lf.x.xyz), dot(d, lf.y.xyz), dot(d, lf.z.xyz));
}

// A point of S (luminaire frame, metres) in world space.
vec3 image_plane_point(vec2 s) {
    return lf.position.xyz + s.x * lf.x.xyz + s.y * lf.y.xyz + lf.plane.z * lf.z.xyz;
}

vec3 filter_plane_point(vec2 u) {
    return lf.position.xyz + u.x * lf.x.xyz + u.y * lf.y.xyz;
}

// Eq. 4.11: the window (texel units, unclamped) through which local point p sees basis m.
vec4 basis_window(uint m, vec3 p) {
    vec2 c = basis_node(m);
    vec2 r = basis_half_support();
    float k = (p.z - lf.plane.z) / p.z;
    vec2 a = plane_to_texels(p.xy + (c - r - p.xy) * k);
    vec2 b = plane_to_texels(p.xy + (c + r - p.xy) * k);
    return vec4(a.x, b.x, a.y, b.y);
}

vec4 clamp_window(vec4 w) {
    return vec4(clamp(w.x, 0.0, float(lf.grid.z)), clamp(w.y, 0.0, float(lf.grid.z)),
                clamp(w.z, 0.0, float(lf.grid.w)), clamp(w.w, 0.0, float(lf.grid.w)));
}

vec4 whole_image() { return vec4(0.0, float(lf.grid.z), 0.0, float(lf.grid.w)); }

// Section 4.3.4: close to S the windows shrink to a point (p on S: A_m = 0 and 1 / |s - p|^3
// infinite), and A_m, a difference of summed-area values, drowns in f32 rounding. Where every
// window is narrower than a texel, the restricted strategies integrate over U instead.
bool near_image_plane(vec3 p) {
    float k = (p.z - lf.plane.z) / p.z;
    vec2 width = 2.0 * k * basis_half_support() * vec2(lf.grid.zw) / lf.image_size.xy;
    return min(width.x, width.y) < 1.0;
}

// The largest luminance of image m over the texels window w (clamped, texel units) touches.
float window_peak(LuminaireImage im, vec4 w) {
    if (!(w.y > w.x && w.w > w.z)) return 0.0;
    uint i0 = min(uint(w.x), im.width - 1u);
    uint i1 = min(uint(ceil(w.y)) - 1u, im.width - 1u);
    uint j0 = min(uint(w.z), im.height - 1u);
    uint j1 = min(uint(ceil(w.w)) - 1u, im.height - 1u);
    float peak = 0.0;
    for (uint j = j0; j <= j1; ++j) {
        for (uint i = i0; i <= i1; ++i) peak = max(peak, luminaire_luminance(im, i, j));
    }
    return peak;
}

// Image m's weight in the split of a point's samples (Eq. 4.16): A_m over the window
// (restricted, uniform; Eq. 4.14) or over the whole image (precomputed); near S (`near`),
// the peak of C_m over the window's texels, which is C_m(p) on S (Lu: "trivially balanced
// according to C_m(s)"), and is positive wherever the window holds light; brute force: 1.
// Below the f32 noise of the summed-area table's differences an image counts as dark.
float image_share(uint m, vec3 p, bool near) {
    uint strategy = lf.options.y;
    if (strategy == STRATEGY_BRUTE_FORCE) return 1.0;
    LuminaireImage im = luminaire_image(m);
    vec4 w = clamp_window(basis_window(m, p));
    if (near) return window_peak(im, w);
    float whole = window_integral(im, whole_image());
    float share = strategy == STRATEGY_PRECOMPUTED ? whole : window_integral(im, w);
    return share > 1e-6 * whole ? share : 0.0;
}

// Whether the point takes the filter-plane estimator of Section 4.3.4.
bool uses_filter_plane(vec3 p) {
    uint strategy = lf.options.y;
    return (strategy == STRATEGY_RESTRICTED || strategy == STRATEGY_UNIFORM) &&
           near_image_plane(p);
}

#endif
