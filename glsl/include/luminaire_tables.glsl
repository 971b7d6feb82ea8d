// Restricted-CDF sampling of a light-field luminaire's images on the GPU (Lu 14 Section
// 4.3.3-4.4; src/sampling/restricted.rs is the f64 mirror, src/methods/lightfield/tables.rs
// builds the tables). Image m is R_s x R_t texels, texel (i, j) covering s in [i, i + 1) and t
// in [j, j + 1) (texel units). A window [s0, s1] x [t0, t1] is sampled with the window's own
// marginal in s, F(s) = the integral of C over [s0, s] x [t0, t1] read from the summed-area
// table (bilinear between its knots: exact for a piecewise-constant image), then t from
// column s's CDF restricted to [t0, t1]; the realised pdf is C / A, A = F(s1) (Eq. 4.14), and
// is computed from the values the draw inverted.
// Knot intervals are found by binary search or Lu's modified secant search. Bindings 30-32.
#ifndef LUMINAIRE_TABLES_GLSL
#define LUMINAIRE_TABLES_GLSL

// The images' RGB texels: image m, row t, column s.
layout(set = 0, binding = 30, std430) readonly buffer LuminaireTexels { vec4 luminaire_texels[]; };
// Per image and column, the inclusive scan over t: (m, s, t).
layout(set = 0, binding = 31, std430) readonly buffer ColumnCdf { float column_cdf[]; };
// Per image, the inclusive summed-area table: (m, t, s) holds [0, s + 1] x [0, t + 1].
layout(set = 0, binding = 32, std430) readonly buffer LuminaireSat { float luminaire_sat[]; };

#define SEARCH_BINARY 0u
#define SEARCH_SECANT 1u

struct LuminaireImage {
    uint m;
    uint width;   // R_s
    uint height;  // R_t
};

float luminaire_luminance(LuminaireImage im, uint i, uint j) {
    vec3 c = luminaire_texels[(im.m * im.height + j) * im.width + i].rgb;
    return max(dot(c, vec3(0.2126, 0.7152, 0.0722)), 0.0);
}

// The summed-area table at knot (i, j): the integral over [0, i] x [0, j].
float sat_knot(LuminaireImage im, uint i, uint j) {
    if (i == 0u || j == 0u) return 0.0;
    return luminaire_sat[(im.m * im.height + j - 1u) * im.width + i - 1u];
}

// The integral over [0, s] x [0, t].
float sat_at(LuminaireImage im, float s, float t) {
    s = clamp(s, 0.0, float(im.width));
    t = clamp(t, 0.0, float(im.height));
    uint i = min(uint(s), im.width - 1u);
    uint j = min(uint(t), im.height - 1u);
    float fs = s - float(i);
    float ft = t - float(j);
    float lower = mix(sat_knot(im, i, j), sat_knot(im, i + 1u, j), fs);
    float upper = mix(sat_knot(im, i, j + 1u), sat_knot(im, i + 1u, j + 1u), fs);
    return mix(lower, upper, ft);
}

// A: the window's integral (texel units).
float window_integral(LuminaireImage im, vec4 w) {
    return max(sat_at(im, w.y, w.w) - sat_at(im, w.x, w.w) - sat_at(im, w.y, w.z) +
                   sat_at(im, w.x, w.z),
               0.0);
}

// Column i's integral over [0, t].
float column_at(LuminaireImage im, uint i, float t) {
    t = clamp(t, 0.0, float(im.height));
    uint j = min(uint(t), im.height - 1u);
    uint base = (im.m * im.width + i) * im.height;
    float below = j == 0u ? 0.0 : column_cdf[base + j - 1u];
    float above = column_cdf[base + j];
    return below + (t - float(j)) * (above - below);
}

// The summed-area table on knot column i, at t: the integral over [0, i] x [0, t].
float sat_on_column(LuminaireImage im, uint i, float t) {
    if (i == 0u) return 0.0;
    t = clamp(t, 0.0, float(im.height));
    uint j = min(uint(t), im.height - 1u);
    return mix(sat_knot(im, i, j), sat_knot(im, i, j + 1u), t - float(j));
}

// Knot k of a search over [lo, hi] starting at integer `first`: clamp(first + k, lo, hi).
float search_knot(uint first, uint k, float lo, float hi) {
    return clamp(float(first + k), lo, hi);
}

// The window's marginal (in_s true) or column i's restricted CDF (in_s false) at knot k;
// `origin` is what the marginal subtracts (the integral over [0, s0] x [t0, t1]). Inside the
// window a knot of the marginal is an integer column: two summed-area reads per row of t.
float knot_value(LuminaireImage im, vec4 w, bool in_s, uint i, uint first, uint k, float below,
                 float origin) {
    if (in_s) {
        uint knot = first + k;
        if (float(knot) > w.x && float(knot) < w.y) {
            return sat_on_column(im, knot, w.w) - sat_on_column(im, knot, w.z) - origin;
        }
        // The window's edges, with the very operations of draw_restricted's total and origin:
        // knot 0 is exactly 0 and the last knot exactly the total, so a target below the
        // total always falls in an interval of the window.
        float s = search_knot(first, k, w.x, w.y);
        return sat_at(im, s, w.w) - sat_at(im, s, w.z) - origin;
    }
    return column_at(im, i, search_knot(first, k, w.z, w.w)) - below;
}

// The knot interval [k, k + 1) of [0, count] holding target (value(k) <= target <
// value(k + 1)); `steps` counts the iterations. The bracket's values are carried from one
// iteration to the next, so each one reads one or two new knots.
uint invert_knots(LuminaireImage im, vec4 w, bool in_s, uint i, uint first, float below,
                  float origin, uint count, float target, uint search, inout uint steps) {
    uint lo = 0u;
    uint hi = count;
    float a = 0.0;
    float b = knot_value(im, w, in_s, i, first, hi, below, origin);
    while (hi - lo > 1u) {
        ++steps;
        if (search == SEARCH_SECANT) {
            float x = b > a ? float(lo) + (target - a) / (b - a) * float(hi - lo) : float(lo);
            uint k = uint(clamp(floor(x), float(lo), float(hi - 1u)));
            float vk = k == lo ? a : knot_value(im, w, in_s, i, first, k, below, origin);
            if (target < vk) {
                hi = k;
                b = vk;
                continue;
            }
            float vk1 = k + 1u == hi ? b : knot_value(im, w, in_s, i, first, k + 1u, below, origin);
            if (target < vk1) return k;
            // The bracket shrinks by at least one knot.
            lo = k + 1u;
            a = vk1;
            if (lo >= hi) break;
        } else {
            uint mid = (lo + hi) / 2u;
            float vm = knot_value(im, w, in_s, i, first, mid, below, origin);
            if (target < vm) {
                hi = mid;
                b = vm;
            } else {
                lo = mid;
                a = vm;
            }
        }
    }
    return min(lo, count - 1u);
}

// Draws a point of window w = (s0, s1, t0, t1) (clamped to the image) from u; false when the
// window holds nothing. `texel` is its texel, `pdf` the density realised (C / A in exact
// arithmetic; texel units), `steps` the search iterations of both inversions.
bool draw_restricted(LuminaireImage im, vec4 w, vec2 u, uint search, out vec2 st,
                     out uvec2 texel, out float pdf, out uint steps) {
    st = vec2(0.0);
    texel = uvec2(0u);
    pdf = 0.0;
    steps = 0u;
    w = vec4(clamp(min(w.x, w.y), 0.0, float(im.width)), clamp(max(w.x, w.y), 0.0, float(im.width)),
             clamp(min(w.z, w.w), 0.0, float(im.height)), clamp(max(w.z, w.w), 0.0, float(im.height)));
    if (!(w.y > w.x && w.w > w.z)) return false;
    float origin = sat_at(im, w.x, w.w) - sat_at(im, w.x, w.z);
    float total = sat_at(im, w.y, w.w) - sat_at(im, w.y, w.z) - origin;
    if (!(total > 0.0)) return false;
    uint first = uint(floor(w.x));
    uint last = clamp(uint(ceil(w.y)), first + 1u, im.width);
    float target = u.x * total;
    uint k = invert_knots(im, w, true, 0u, first, 0.0, origin, last - first, target, search, steps);
    float a = search_knot(first, k, w.x, w.y);
    float b = search_knot(first, k + 1u, w.x, w.y);
    float fa = knot_value(im, w, true, 0u, first, k, 0.0, origin);
    float fb = knot_value(im, w, true, 0u, first, k + 1u, 0.0, origin);
    float s = fb > fa ? a + (target - fa) / (fb - fa) * (b - a) : a;
    uint i = min(first + k, im.width - 1u);
    float below = column_at(im, i, w.z);
    float mass = column_at(im, i, w.w) - below;
    if (!(mass > 0.0)) return false;
    uint first_t = uint(floor(w.z));
    uint last_t = clamp(uint(ceil(w.w)), first_t + 1u, im.height);
    float target_t = u.y * mass;
    uint kt = invert_knots(im, w, false, i, first_t, below, 0.0, last_t - first_t, target_t, search,
                           steps);
    float at = search_knot(first_t, kt, w.z, w.w);
    float bt = search_knot(first_t, kt + 1u, w.z, w.w);
    float ga = column_at(im, i, at) - below;
    float gb = column_at(im, i, bt) - below;
    float t = gb > ga ? at + (target_t - ga) / (gb - ga) * (bt - at) : at;
    uint j = min(first_t + kt, im.height - 1u);
    st = vec2(clamp(s, w.x, w.y), clamp(t, w.z, w.w));
    texel = uvec2(i, j);
    // The density the draw realises, from the very values it inverted: the marginal's slope
    // over [a, b] and the column's over [at, bt]. In exact arithmetic that is C / A (Eq. 4.14:
    // the slopes are the column's mass over [t0, t1] and C); in f32 the summed-area
    // differences carry rounding, and dividing by what was drawn keeps the estimate unbiased.
    if (!(fb > fa && gb > ga)) return false;
    pdf = (fb - fa) / (b - a) / total * ((gb - ga) / (bt - at)) / mass;
    return pdf > 0.0 && luminaire_luminance(im, i, j) > 0.0;
}

#endif
