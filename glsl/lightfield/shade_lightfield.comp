#version 450
// The `lightfield` method's step 2 (Lu 14 Section 4.3-4.5): the direct light of one placed
// light-field luminaire at every G-buffer point p, A(p) coming from step 1
// (estimate_luminaire_areas.comp). Per image m, K_m = round(K A_m / A), at least 1 where
// A_m > 0 (so no image that holds light is dropped: each I_m keeps its own unbiased estimate
// whatever K_m) and at most K_max (Eq. 4.16), then per strategy:
//   restricted (Lu's): s drawn in the window of Eq. 4.11 by the windowed restricted CDFs
//     (luminaire_tables.glsl: realised pdf C / A_m, Eq. 4.14);
//   uniform: s uniform over the window (Fig. 4.14's comparison);
//   precomputed: s by one CDF over the whole image (no restriction, Fig. 4.13's), K_m by the
//     images' totals; samples outside the window carry nothing;
//   brute force: s uniform over the whole image plane, K / M per image: the reference.
// Each sample s (texel units, pdf q per texel area) contributes, with u where the line p-s
// meets U and Delta = p.z - delta,
//   f(wo, wi) cos(n, wi) C_m(s) Psi_m(u -> s) Delta / |s - p|^3 / (q texels_per_m2) / K_m,
// Psi_m = Phi_m(u) |s - u|^4 / delta^2 (Eq. 4.1, 4.18); C_m is RGB and its luminance drives
// the pdf, so the colour ratio of Section 4.4 comes out of RGB / Y.
// Close to S (Section 4.3.4; luminaire.glsl's near_image_plane) restricted and uniform
// integrate over U instead: u uniform over basis m's support box B_m, s where the line u-p
// meets S, contribution f cos C_m(s) Psi_m(u -> s) p.z / |u - p|^3 |B_m| / K_m (unbiased at
// every p beyond S, so the switch adds no bias), K_m by the peak of C_m over the window.
// Points at or behind S get nothing.
// Samples: Halton points (bases 2 and 3; Section 4.5.3: every prefix is well spread, so the
// K_m points of any image are) under a Cranley-Patterson rotation drawn per pixel, frame and
// image, or (shared) per frame and image, the same for every pixel.
// Visibility: a shadow ray per sample, none, or (averaged: Section 4.5.2's approximation) one
// per image toward the image's median point (its CDFs at 1/2) standing for all its samples.
// `sampling_only` (irad bench lightfield) draws the samples and shades nothing: the time of
// sampling alone. The host splits each pixel's samples, numbered image after image, into
// dispatches of at most SAMPLES_PER_DISPATCH (src/methods/lightfield/mod.rs), so no
// invocation loops more than lavapipe's limit allows.

#extension GL_GOOGLE_include_directive : require

layout(local_size_x = 8, local_size_y = 8, local_size_z = 1) in;

#include "bvh.glsl"
#include "scene.glsl"
#include "sampling.glsl"
#include "bsdf.glsl"
#include "gbuffer.glsl"
#include "radiance.glsl"
#include "luminaire.glsl"

// Per pixel, summed over frames and luminaires: the samples drawn.
layout(set = 0, binding = 35, std430) buffer LuminaireSampleCounts { float sample_counts[]; };
// Per pixel: A(p), from estimate_luminaire_areas.comp.
layout(set = 0, binding = 36, std430) readonly buffer LuminaireAreas { float luminaire_areas[]; };

#define VISIBILITY_NONE 0u
#define VISIBILITY_PER_SAMPLE 1u
#define VISIBILITY_AVERAGED 2u

layout(push_constant) uniform ShadeParams {
    uint frame;
    uint seed;
    uint search;
    uint shared_samples;  // 1: the same rotation for every pixel
    uint visibility;
    uint sampling_only;
    // This dispatch's part of the pixel's samples, numbered image after image (image m's
    // K_m samples follow those of the images before it): [sample_begin, sample_end). The
    // parts' sums add up to Eq. 4.18.
    uint sample_begin;
    uint sample_end;
} params;

// One light sample of image m: the point on S (luminaire frame, metres), and the light it
// brings per unit of f cos, divided by its pdf. False when it brings nothing.
struct LightSample {
    vec2 s;
    vec3 value;
};

// A sample on S by the strategy's pdf (Eq. 4.17-4.18).
bool sample_image_plane(uint m, vec3 p, vec4 area, vec2 u, inout float sink,
                        out LightSample ls) {
    ls.s = vec2(0.0);
    ls.value = vec3(0.0);
    uint strategy = lf.options.y;
    LuminaireImage im = luminaire_image(m);
    vec2 st;
    float q;
    uvec2 texel;
    if (strategy == STRATEGY_RESTRICTED || strategy == STRATEGY_PRECOMPUTED) {
        uint steps;
        if (!draw_restricted(im, area, u, params.search, st, texel, q, steps)) return false;
    } else {
        float window_texels = (area.y - area.x) * (area.w - area.z);
        if (!(window_texels > 0.0)) return false;
        st = vec2(mix(area.x, area.y, u.x), mix(area.z, area.w, u.y));
        texel = uvec2(min(uint(st.x), lf.grid.z - 1u), min(uint(st.y), lf.grid.w - 1u));
        q = 1.0 / window_texels;
    }
    if (params.sampling_only != 0u) {
        sink += st.x + st.y + q;
        return false;
    }
    vec3 c = luminaire_texels[(m * lf.grid.w + texel.y) * lf.grid.z + texel.x].rgb;
    if (!(max(max(c.r, c.g), c.b) > 0.0)) return false;
    vec2 s = texels_to_plane(st);
    float delta = lf.plane.z;
    // u: where the line from p through s meets U.
    vec2 uf = p.xy + (s - p.xy) * (p.z / (p.z - delta));
    float basis = phi(m, uf);
    if (!(basis > 0.0)) return false;
    vec3 su = vec3(s - uf, delta);
    float su2 = dot(su, su);
    float psi = basis * su2 * su2 / (delta * delta);
    float r = length(vec3(s, delta) - p);
    ls.s = s;
    ls.value = c * psi * (p.z - delta) / (r * r * r) / (q * lf.image_size.z);
    return true;
}

// Section 4.3.4: u uniform over basis m's support box, s where the line u-p meets S.
bool sample_filter_plane(uint m, vec3 p, vec2 u, inout float sink, out LightSample ls) {
    ls.s = vec2(0.0);
    ls.value = vec3(0.0);
    vec2 half_support = basis_half_support();
    vec2 uf = basis_node(m) + (2.0 * u - 1.0) * half_support;
    float delta = lf.plane.z;
    vec2 s = uf + (p.xy - uf) * (delta / p.z);
    if (params.sampling_only != 0u) {
        sink += abs(s.x) + abs(s.y);
        return false;
    }
    vec2 st = plane_to_texels(s);
    if (any(lessThan(st, vec2(0.0))) || any(greaterThanEqual(st, vec2(lf.grid.zw)))) return false;
    uvec2 texel = uvec2(st);
    vec3 c = luminaire_texels[(m * lf.grid.w + texel.y) * lf.grid.z + texel.x].rgb;
    if (!(max(max(c.r, c.g), c.b) > 0.0)) return false;
    float basis = phi(m, uf);
    if (!(basis > 0.0)) return false;
    vec3 su = vec3(s - uf, delta);
    float su2 = dot(su, su);
    float psi = basis * su2 * su2 / (delta * delta);
    float r = length(vec3(uf, 0.0) - p);
    ls.s = s;
    ls.value = c * psi * p.z / (r * r * r) * (4.0 * half_support.x * half_support.y);
    return true;
}

void main() {
    uvec2 pixel = gl_GlobalInvocationID.xy;
    if (pixel.x >= scene.size.x || pixel.y >= scene.size.y) return;
    uint index = pixel.y * scene.size.x + pixel.x;
    float total = luminaire_areas[index];
    if (!(total > 0.0)) return;
    GBufferTexel g = gbuffer[index];
    vec3 wo, side, n;
    if (!gbuffer_surface(g, wo, side, n)) return;
    Material mat = gbuffer_material(g);
    vec3 pw = g.position.xyz;
    vec3 origin = offset_origin(pw, side);
    vec3 p = to_luminaire(pw);
    if (!(p.z > lf.plane.z)) return;
    uint images = luminaire_images();
    uint strategy = lf.options.y;
    uint k_total = lf.options.z;
    uint k_max = max(lf.options.w, 1u);
    bool near = uses_filter_plane(p);

    vec3 sum = vec3(0.0);
    float drawn = 0.0;
    float sink = 0.0;
    uint first = 0u;  // the number of image m's first sample among the pixel's
    for (uint m = 0u; m < images && first < params.sample_end; ++m) {
        float share = image_share(m, p, near);
        if (!(share > 0.0)) continue;
        uint count = strategy == STRATEGY_BRUTE_FORCE
                         ? max(k_total / images, 1u)
                         : clamp(uint(round(float(k_total) * share / total)), 1u, k_max);
        uint k_begin = max(params.sample_begin, first) - first;
        uint k_end = min(params.sample_end - first, count);
        first += count;
        if (k_begin >= k_end) continue;
        vec4 area = strategy == STRATEGY_RESTRICTED || strategy == STRATEGY_UNIFORM
                        ? clamp_window(basis_window(m, p))
                        : whole_image();
        LuminaireImage im = luminaire_image(m);
        // Averaged visibility: one shadow ray toward the image's median point.
        bool image_visible = true;
        if (params.visibility == VISIBILITY_AVERAGED && params.sampling_only == 0u) {
            vec2 st;
            uvec2 texel;
            float q;
            uint steps;
            if (draw_restricted(im, whole_image(), vec2(0.5), SEARCH_BINARY, st, texel, q, steps)) {
                vec3 sw = image_plane_point(texels_to_plane(st));
                image_visible = !trace_any(origin, sw - origin, 0.9999);
            }
        }
        uint key = params.shared_samples != 0u ? 0xffffffffu : index;
        vec2 rotation = vec2(random(params.seed, key, params.frame * images + m, 0u),
                             random(params.seed, key, params.frame * images + m, 1u));
        vec3 image_sum = vec3(0.0);
        for (uint k = k_begin; k < k_end; ++k) {
            vec2 u = vec2(shifted_halton(2u, k, rotation.x), shifted_halton(3u, k, rotation.y));
            drawn += 1.0;
            LightSample ls;
            bool lit = near ? sample_filter_plane(m, p, u, sink, ls)
                            : sample_image_plane(m, p, area, u, sink, ls);
            if (!lit) continue;
            vec3 sw = image_plane_point(ls.s);
            vec3 wi = normalize(sw - pw);
            float cos_i = dot(n, wi);
            if (cos_i <= 0.0 || dot(side, wi) <= 0.0) continue;
            vec3 f = bsdf_eval(mat, n, wo, wi);
            if (!(max(max(f.r, f.g), f.b) > 0.0)) continue;
            bool visible = params.visibility == VISIBILITY_PER_SAMPLE
                               ? !trace_any(origin, sw - origin, 0.9999)
                               : image_visible;
            if (visible) image_sum += f * cos_i * ls.value;
        }
        sum += image_sum / float(count);
    }
    // Never true (the sink sums non-negative values): keeps the sampling of a sampling-only
    // run from being compiled away.
    if (sink < 0.0) drawn = -1.0;
    sample_counts[index] += drawn;
    if (params.sampling_only == 0u) accumulate_radiance(index, sum);
}
