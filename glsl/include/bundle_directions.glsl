// Tokuyoshi 12 Section 3.3: the density of the global ray bundles' directions. A point casts
// along +w or -w, whichever faces its side, so its ray direction v has the density
// p_r(v) = q(v) + q(-v), where q is the density over the sphere that w is drawn from:
//   uniform (indoor scenes, dynamic maps): q = 1 / (4 pi), p_r = 1 / (2 pi);
//   environment (Eq. 2): q(w) = (Le(w) + Lo) / integral of (Le + Lo) over the sphere, so that
//   p_r(v) = (Le(v) + Le(-v) + 2 Lo) / integral of (Le + Lo), the paper's pdf.
// The environment table (weigh_bundle_directions.comp, then the GPU scans) has two levels, so
// that no texel's share is a difference of two large running sums: per row of the map, the
// prefix sum of (Y(Le) + Lo) times the texel's solid angle; over the rows, the prefix sum of
// the row totals. w's row is drawn by binary search over the second, its texel by binary
// search within the row, and w is uniform in the texel's solid angle, so q is piecewise
// constant: the texel's realised probability (the row's width in the row scan over the total,
// times the texel's width in its row over the row's total) over its solid angle. Needs
// scene.glsl, sampling.glsl and envmap.glsl; bindings 15-17.
#ifndef BUNDLE_DIRECTIONS_GLSL
#define BUNDLE_DIRECTIONS_GLSL

#define BUNDLE_DIRECTIONS_UNIFORM 0u
#define BUNDLE_DIRECTIONS_ENVIRONMENT 1u

// Per row, the inclusive prefix sum of the texel weights (the row's total is its last value).
layout(set = 0, binding = 15, std430) readonly buffer BundleDirectionCdf { float bundle_direction_cdf[]; };
// The inclusive prefix sum of the row totals.
layout(set = 0, binding = 16, std430) readonly buffer BundleRowCdf { float bundle_row_cdf[]; };
layout(set = 0, binding = 17, std430) readonly buffer BundleDirectionTotal { float bundle_direction_total[]; };

// A table that sums to zero (a black map with Lo = 0) falls back to uniform directions.
uint bundle_directions_mode(uint mode) {
    if (mode == BUNDLE_DIRECTIONS_UNIFORM) return mode;
    return bundle_direction_total[0] > 0.0 ? mode : BUNDLE_DIRECTIONS_UNIFORM;
}

// The width of entry i of an inclusive scan (never negative: float rounding may dip by one
// step where the scan's blocks meet).
float scan_width(float upper, float lower) {
    return max(upper - lower, 0.0);
}

// q over the sphere in texel t of the environment table.
float bundle_texel_density(uint t) {
    uint w = scene.env_size.x;
    uint j = t / w;
    float rows = bundle_row_cdf[j] - (j == 0u ? 0.0 : bundle_row_cdf[j - 1u]);
    float row_total = bundle_direction_cdf[j * w + w - 1u];
    if (!(rows > 0.0) || !(row_total > 0.0)) return 0.0;
    float below = t % w == 0u ? 0.0 : bundle_direction_cdf[t - 1u];
    float p = rows / bundle_direction_total[0] *
              (scan_width(bundle_direction_cdf[t], below) / row_total);
    return p / env_texel_solid_angle(j);
}

// p_r(v): the density of a point's bundle ray direction v over its hemisphere.
float bundle_pdf(uint mode, vec3 v) {
    if (bundle_directions_mode(mode) == BUNDLE_DIRECTIONS_UNIFORM) return 0.5 * INV_PI;
    return bundle_texel_density(env_texel_index(v)) + bundle_texel_density(env_texel_index(-v));
}

// The first of entries [begin, begin + count) of an inclusive scan whose value exceeds r,
// stepped back over empty entries where r rounded up to the last value.
uint search_scan(uint begin, uint count, float r, bool rows) {
    uint lo = 0u;
    uint hi = count - 1u;
    while (lo < hi) {
        uint mid = (lo + hi) / 2u;
        float upper = rows ? bundle_row_cdf[begin + mid] : bundle_direction_cdf[begin + mid];
        if (r < upper) hi = mid; else lo = mid + 1u;
    }
    while (lo > 0u) {
        float upper = rows ? bundle_row_cdf[begin + lo] : bundle_direction_cdf[begin + lo];
        float lower = rows ? bundle_row_cdf[begin + lo - 1u] : bundle_direction_cdf[begin + lo - 1u];
        if (upper > lower) break;
        --lo;
    }
    return lo;
}

// Draws w from q and returns it with p_r(w): u.x picks the row, u.y the texel in it, u.zw
// place w in the texel (uniform: u.xy place w).
vec3 sample_bundle_direction(uint mode, vec4 u, out float p_r) {
    if (bundle_directions_mode(mode) == BUNDLE_DIRECTIONS_UNIFORM) {
        float z = 1.0 - 2.0 * u.x;
        float s = sqrt(max(0.0, 1.0 - z * z));
        p_r = 0.5 * INV_PI;
        return vec3(s * cos(2.0 * PI * u.y), s * sin(2.0 * PI * u.y), z);
    }
    uint w = scene.env_size.x;
    uint h = scene.env_size.y;
    uint j = search_scan(0u, h, u.x * bundle_direction_total[0], true);
    uint i = search_scan(j * w, w, u.y * bundle_direction_cdf[j * w + w - 1u], false);
    float phi = 2.0 * PI * (float(i) + u.z) / float(w);
    float cos_top = cos(PI * float(j) / float(h));
    float cos_bottom = cos(PI * float(j + 1u) / float(h));
    float y = mix(cos_top, cos_bottom, u.w);
    float radius = sqrt(max(0.0, 1.0 - y * y));
    vec3 d = vec3(radius * sin(phi), y, -radius * cos(phi));
    // The sampled texel's own density (not the one d's coordinates round into), plus -d's.
    p_r = bundle_texel_density(j * w + i) + bundle_texel_density(env_texel_index(-d));
    return d;
}

#endif
