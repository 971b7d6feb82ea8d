// A sampling table over the environment map's texels, rebuilt on the GPU (src/methods/
// equirect_table.rs): each texel weighted by (Y(Le) + offset) times its solid angle
// (weigh_equirect_texels.comp), then the prefix sum within every row and over the row totals
// (two levels, so that no texel's share is a difference of two large running sums). A
// direction is drawn by choosing the row by binary search over the second scan, the texel
// by binary search within the row, and a point uniform in the texel's solid angle, so the
// density over the sphere, q, is piecewise constant: the texel's realised probability (its
// row's share of the total times its share of the row, the numbers the searches see) over its
// solid angle. With offset 0 this is the pbrt/Mitsuba latitude-longitude sampler (luminance
// times sin(theta), in the exact solid-angle form). Needs scene.glsl, sampling.glsl and
// envmap.glsl; bindings 15-17.
#ifndef EQUIRECT_TABLE_GLSL
#define EQUIRECT_TABLE_GLSL

// Per row, the inclusive prefix sum of the texel weights (the row's total is its last value).
layout(set = 0, binding = 15, std430) readonly buffer EquirectCdf { float equirect_cdf[]; };
// The inclusive prefix sum of the row totals.
layout(set = 0, binding = 16, std430) readonly buffer EquirectRowCdf { float equirect_row_cdf[]; };
layout(set = 0, binding = 17, std430) readonly buffer EquirectTotal { float equirect_total[]; };

bool equirect_table_empty() {
    return !(equirect_total[0] > 0.0);
}

// q over the sphere in texel t.
float equirect_texel_density(uint t) {
    uint w = scene.env_size.x;
    uint j = t / w;
    float rows = equirect_row_cdf[j] - (j == 0u ? 0.0 : equirect_row_cdf[j - 1u]);
    float row_total = equirect_cdf[j * w + w - 1u];
    if (!(rows > 0.0) || !(row_total > 0.0)) return 0.0;
    float below = t % w == 0u ? 0.0 : equirect_cdf[t - 1u];
    float p = rows / equirect_total[0] * (max(equirect_cdf[t] - below, 0.0) / row_total);
    return p / env_texel_solid_angle(j);
}

// q(d).
float equirect_density(vec3 d) {
    return equirect_texel_density(env_texel_index(d));
}

// The first of entries [begin, begin + count) of an inclusive scan whose value exceeds r,
// stepped back over empty entries where r rounded up to the last value.
uint equirect_search(uint begin, uint count, float r, bool rows) {
    uint lo = 0u;
    uint hi = count - 1u;
    while (lo < hi) {
        uint mid = (lo + hi) / 2u;
        float upper = rows ? equirect_row_cdf[begin + mid] : equirect_cdf[begin + mid];
        if (r < upper) hi = mid; else lo = mid + 1u;
    }
    while (lo > 0u) {
        float upper = rows ? equirect_row_cdf[begin + lo] : equirect_cdf[begin + lo];
        float lower = rows ? equirect_row_cdf[begin + lo - 1u] : equirect_cdf[begin + lo - 1u];
        if (upper > lower) break;
        --lo;
    }
    return lo;
}

// Draws a direction from q: u.x picks the row, u.y the texel in it, u.zw place the direction
// in the texel; `texel` is the texel drawn (its density is equirect_texel_density(texel)).
vec3 equirect_sample(vec4 u, out uint texel) {
    uint w = scene.env_size.x;
    uint h = scene.env_size.y;
    uint j = equirect_search(0u, h, u.x * equirect_total[0], true);
    uint i = equirect_search(j * w, w, u.y * equirect_cdf[j * w + w - 1u], false);
    texel = j * w + i;
    float phi = 2.0 * PI * (float(i) + u.z) / float(w);
    float cos_top = cos(PI * float(j) / float(h));
    float cos_bottom = cos(PI * float(j + 1u) / float(h));
    float y = mix(cos_top, cos_bottom, u.w);
    float radius = sqrt(max(0.0, 1.0 - y * y));
    return vec3(radius * sin(phi), y, -radius * cos(phi));
}

#endif
