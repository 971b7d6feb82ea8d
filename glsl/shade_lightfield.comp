#version 450
// The `lightfield` method's shading (Lu 14 Section 4.3-4.4): the direct light of one placed
// light-field luminaire at every G-buffer point p, with a shadow ray per sample. In the
// luminaire's frame (filter plane z = 0, image plane z = delta; LuminaireFrame), for every image
// m: the window of Eq. 4.11 through which p sees basis m's support, and then per strategy:
//   restricted (0, Lu's): A_m(p) from the summed-area table (Eq. 4.14), K_m = round(K A_m / A),
//     at least 1 where A_m > 0 and at most K_max (Eq. 4.16), s drawn in the window by the
//     windowed restricted CDFs (luminaire_tables.glsl: realised pdf C / A_m);
//   uniform (1): the same K_m, s uniform over the window (Fig. 4.14's comparison);
//   precomputed (2): one CDF over the whole image (no restriction, Fig. 4.13's), K_m by the
//     images' totals; samples outside the support carry nothing;
//   brute-force (3): s uniform over the whole image plane, K / M per image: the reference.
// Each sample s (texel units, pdf q per texel area) contributes, with u where the line p-s
// meets the filter plane and Delta = p.z - delta,
//   f(wo, wi) cos(n, wi) C_m(s) Psi_m(u -> s) Delta / |s - p|^3 / (q texels_per_m2) / K_m,
// Psi_m = Phi_m(u) |s - u|^4 / delta^2 (Eq. 4.1), C_m RGB (its luminance drives the pdf, so
// the colour ratio of Section 4.4 comes out of RGB / Y). Points at or behind the image plane
// get nothing here. Samples: random per (seed, pixel, frame, sample), or (shared) image m's
// K_m samples are the first K_m points of a scrambled Halton sequence that every pixel shares
// in the frame (Section 4.5.3: prefixes stay well spread). Visibility: a shadow ray per sample,
// or (averaged, Section 4.5.2's approximation) one per image toward the image's median point
// (its CDFs at 1/2), standing for all of that image's samples.

#extension GL_GOOGLE_include_directive : require

layout(local_size_x = 8, local_size_y = 8, local_size_z = 1) in;

#include "bvh.glsl"
#include "scene.glsl"
#include "sampling.glsl"
#include "bsdf.glsl"
#include "gbuffer.glsl"
#include "radiance.glsl"
#include "halton.glsl"
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
// Per pixel, summed over frames and luminaires: the samples drawn.
layout(set = 0, binding = 35, std430) buffer LuminaireSampleCounts { float sample_counts[]; };

layout(push_constant) uniform ShadeParams {
    uint frame;
    uint seed;
    uint search;
    uint shared_samples;  // 1: Halton prefixes shared by every pixel
    uint averaged;        // 1: one shadow ray per image (Section 4.5.2)
} params;

#define STRATEGY_RESTRICTED 0u
#define STRATEGY_UNIFORM 1u
#define STRATEGY_PRECOMPUTED 2u
#define STRATEGY_BRUTE_FORCE 3u

float basis_weight(float x) {
    float a = abs(x);
    if (lf.options.x == 0u) return max(1.0 - a, 0.0);
    if (a < 0.5) return 0.75 - a * a;
    if (a < 1.5) return 0.5 * (1.5 - a) * (1.5 - a);
    return 0.0;
}

vec2 node(uint m) {
    uint i = m % lf.grid.x;
    uint j = m / lf.grid.x;
    return vec2((float(i) - 0.5 * float(lf.grid.x - 1u)) * lf.plane.x,
                (float(j) - 0.5 * float(lf.grid.y - 1u)) * lf.plane.y);
}

float phi(uint m, vec2 u) {
    vec2 c = node(m);
    return basis_weight((u.x - c.x) / lf.plane.x) * basis_weight((u.y - c.y) / lf.plane.y);
}

vec2 plane_to_texels(vec2 s) {
    return (s / lf.image_size.xy + 0.5) * vec2(lf.grid.zw);
}

vec2 texels_to_plane(vec2 t) {
    return (t / vec2(lf.grid.zw) - 0.5) * lf.image_size.xy;
}

// Eq. 4.11: the window (texel units, unclamped) through which local point p sees basis m.
vec4 basis_window(uint m, vec3 p) {
    vec2 c = node(m);
    vec2 r = lf.plane.w * lf.plane.xy;
    float k = (p.z - lf.plane.z) / p.z;
    vec2 a = plane_to_texels(p.xy + (c - r - p.xy) * k);
    vec2 b = plane_to_texels(p.xy + (c + r - p.xy) * k);
    return vec4(a.x, b.x, a.y, b.y);
}

vec4 clamp_window(vec4 w) {
    return vec4(clamp(w.x, 0.0, float(lf.grid.z)), clamp(w.y, 0.0, float(lf.grid.z)),
                clamp(w.z, 0.0, float(lf.grid.w)), clamp(w.w, 0.0, float(lf.grid.w)));
}

void main() {
    uvec2 pixel = gl_GlobalInvocationID.xy;
    if (pixel.x >= scene.size.x || pixel.y >= scene.size.y) return;
    uint index = pixel.y * scene.size.x + pixel.x;
    GBufferTexel g = gbuffer[index];
    vec3 wo, side, n;
    if (!gbuffer_surface(g, wo, side, n)) return;
    Material mat = materials[floatBitsToUint(g.shading_normal.w)];
    vec3 pw = g.position.xyz;
    vec3 origin = offset_origin(pw, side);
    vec3 d = pw - lf.position.xyz;
    vec3 p = vec3(dot(d, lf.x.xyz), dot(d, lf.y.xyz), dot(d, lf.z.xyz));
    float delta = lf.plane.z;
    float big_delta = p.z - delta;
    if (!(big_delta > 0.0)) return;
    uint images = lf.grid.x * lf.grid.y;
    uint strategy = lf.options.y;
    uint k_total = lf.options.z;
    uint k_max = max(lf.options.w, 1u);
    float texels_per_m2 = lf.image_size.z;

    // The images' shares: A_m over the window (restricted, uniform) or the image's total
    // (precomputed); brute force gives each image K / M.
    float total = 0.0;
    for (uint m = 0u; m < images; ++m) {
        LuminaireImage im = LuminaireImage(m, lf.grid.z, lf.grid.w);
        vec4 w = strategy == STRATEGY_PRECOMPUTED
                     ? vec4(0.0, float(lf.grid.z), 0.0, float(lf.grid.w))
                     : clamp_window(basis_window(m, p));
        total += window_integral(im, w);
    }
    if (!(total > 0.0) && strategy != STRATEGY_BRUTE_FORCE) return;

    vec3 sum = vec3(0.0);
    float drawn = 0.0;
    uint sample_base = params.frame * (images * k_max + k_total);
    uint sample_index = 0u;
    for (uint m = 0u; m < images; ++m) {
        LuminaireImage im = LuminaireImage(m, lf.grid.z, lf.grid.w);
        vec4 w = clamp_window(basis_window(m, p));
        vec4 whole = vec4(0.0, float(lf.grid.z), 0.0, float(lf.grid.w));
        float share;
        uint count;
        if (strategy == STRATEGY_BRUTE_FORCE) {
            count = max(k_total / images, 1u);
        } else {
            share = window_integral(im, strategy == STRATEGY_PRECOMPUTED ? whole : w);
            // Below f32 noise of the summed-area table's differences: nothing there.
            float noise = 1e-6 * window_integral(im, whole);
            if (!(share > noise)) continue;
            count = clamp(uint(round(float(k_total) * share / total)), 1u, k_max);
        }
        vec4 area = strategy == STRATEGY_RESTRICTED || strategy == STRATEGY_UNIFORM ? w : whole;
        float window_texels = (area.y - area.x) * (area.w - area.z);
        if (!(window_texels > 0.0)) continue;
        // Averaged visibility: one shadow ray toward the image's median point.
        bool image_visible = true;
        if (params.averaged != 0u) {
            vec2 st;
            uvec2 texel;
            float q;
            uint steps;
            if (draw_restricted(im, whole, vec2(0.5), SEARCH_BINARY, st, texel, q, steps)) {
                vec2 s = texels_to_plane(st);
                vec3 sw = lf.position.xyz + s.x * lf.x.xyz + s.y * lf.y.xyz + delta * lf.z.xyz;
                image_visible = !trace_any(origin, sw - origin, 0.9999);
            }
        }
        uint scramble = pcg_hash(params.seed ^ pcg_hash(params.frame * 977u + m));
        vec3 image_sum = vec3(0.0);
        for (uint k = 0u; k < count; ++k) {
            uint si = sample_base + sample_index++;
            vec2 u = params.shared_samples != 0u
                         ? vec2(halton(0u, k, scramble), halton(1u, k, scramble))
                         : vec2(random(params.seed, index, si, 0u), random(params.seed, index, si, 1u));
            drawn += 1.0;
            vec2 st;
            float q;
            uvec2 texel;
            if (strategy == STRATEGY_RESTRICTED || strategy == STRATEGY_PRECOMPUTED) {
                uint steps;
                if (!draw_restricted(im, area, u, params.search, st, texel, q, steps)) continue;
            } else {
                st = vec2(mix(area.x, area.y, u.x), mix(area.z, area.w, u.y));
                texel = uvec2(min(uint(st.x), lf.grid.z - 1u), min(uint(st.y), lf.grid.w - 1u));
                q = 1.0 / window_texels;
            }
            vec3 c = luminaire_texels[(m * lf.grid.w + texel.y) * lf.grid.z + texel.x].rgb;
            if (!(max(max(c.r, c.g), c.b) > 0.0)) continue;
            vec2 s = texels_to_plane(st);
            // u: where the line from p through s meets the filter plane.
            vec2 uf = p.xy + (s - p.xy) * (p.z / (p.z - delta));
            float basis = phi(m, uf);
            if (!(basis > 0.0)) continue;
            vec3 su = vec3(s - uf, delta);
            float su2 = dot(su, su);
            float psi = basis * su2 * su2 / (delta * delta);
            vec3 sw = lf.position.xyz + s.x * lf.x.xyz + s.y * lf.y.xyz + delta * lf.z.xyz;
            vec3 to_s = sw - pw;
            float r = length(to_s);
            vec3 wi = to_s / r;
            float cos_i = dot(n, wi);
            if (cos_i <= 0.0 || dot(side, wi) <= 0.0) continue;
            vec3 f = bsdf_eval(mat, n, wo, wi);
            if (!(max(max(f.r, f.g), f.b) > 0.0)) continue;
            if (params.averaged != 0u ? !image_visible : trace_any(origin, sw - origin, 0.9999)) {
                continue;
            }
            image_sum += f * cos_i * c * psi * big_delta / (r * r * r) / (q * texels_per_m2);
        }
        sum += image_sum / float(count);
    }
    sample_counts[index] += drawn;
    accumulate_radiance(index, sum);
}
