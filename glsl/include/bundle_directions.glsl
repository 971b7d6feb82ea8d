// Tokuyoshi 12 Section 3.3: the density of the global ray bundles' directions. A point casts
// along +w or -w, whichever faces its side, so its ray direction v has the density
// p_r(v) = q(v) + q(-v), where q is the density over the sphere that w is drawn from:
//   uniform (indoor scenes, dynamic maps): q = 1 / (4 pi), p_r = 1 / (2 pi);
//   environment (Eq. 2): q(w) = (Le(w) + Lo) / integral of (Le + Lo) over the sphere, so that
//   p_r(v) = (Le(v) + Le(-v) + 2 Lo) / integral of (Le + Lo), the paper's pdf; q is the
//   equirectangular table (equirect_table.glsl) built with offset Lo.
// Needs scene.glsl, sampling.glsl and envmap.glsl; bindings 15-17.
#ifndef BUNDLE_DIRECTIONS_GLSL
#define BUNDLE_DIRECTIONS_GLSL

#include "equirect_table.glsl"

#define BUNDLE_DIRECTIONS_UNIFORM 0u
#define BUNDLE_DIRECTIONS_ENVIRONMENT 1u

// A table that sums to zero (a black map with Lo = 0) falls back to uniform directions.
uint bundle_directions_mode(uint mode) {
    if (mode == BUNDLE_DIRECTIONS_UNIFORM) return mode;
    return equirect_table_empty() ? BUNDLE_DIRECTIONS_UNIFORM : mode;
}

// p_r(v): the density of a point's bundle ray direction v over its hemisphere.
float bundle_pdf(uint mode, vec3 v) {
    if (bundle_directions_mode(mode) == BUNDLE_DIRECTIONS_UNIFORM) return 0.5 * INV_PI;
    return equirect_density(v) + equirect_density(-v);
}

// Draws w and returns it with p_r(w): u.x picks the row, u.y the texel in it, u.zw place w in
// the texel (uniform: u.xy place w).
vec3 sample_bundle_direction(uint mode, vec4 u, out float p_r) {
    if (bundle_directions_mode(mode) == BUNDLE_DIRECTIONS_UNIFORM) {
        float z = 1.0 - 2.0 * u.x;
        float s = sqrt(max(0.0, 1.0 - z * z));
        p_r = 0.5 * INV_PI;
        return vec3(s * cos(2.0 * PI * u.y), s * sin(2.0 * PI * u.y), z);
    }
    uint texel;
    vec3 d = equirect_sample(u, texel);
    // The sampled texel's own density (not the one d's coordinates round into), plus -d's.
    p_r = equirect_texel_density(texel) + equirect_density(-d);
    return d;
}

#endif
