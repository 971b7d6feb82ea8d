// The per-frame cube-map sampling table of the `env` method (Lu 14 Section 3.3, Alg. 1): from
// the cube texels' weights (weigh_env_cube.comp), per face row the prefix sum of its texels'
// weights, per face the prefix sum of its row totals, and the face totals I_f. Within face f
// a texel is drawn with its realised probability P (its row's share of the face's row scan,
// times its share of the row's scan: the same numbers the binary searches see) and the
// direction is uniform in (u, v) over it, so the solid-angle density given the face is
//   pdf_L(w | f) = P * R^2 / 4 * (1 + u^2 + v^2)^(3/2)
// (Lu Eq. 3.3, with the weight's exact solid angle in P). Bindings 21-23; needs cubemap.glsl.
#ifndef ENV_CUBE_GLSL
#define ENV_CUBE_GLSL

// Per face row (f R + j): the inclusive scan of its texels' weights.
layout(set = 0, binding = 21, std430) readonly buffer CubeRowCdf { float cube_row_cdf[]; };
// Per face (f R + j): the inclusive scan of its rows' totals.
layout(set = 0, binding = 22, std430) readonly buffer CubeFaceCdf { float cube_face_cdf[]; };
// I_f: the face totals.
layout(set = 0, binding = 23, std430) readonly buffer CubeFaceTotals { float cube_face_totals[]; };

// The realised probability of texel (i, j) given face f.
float cube_texel_probability(uint f, uint i, uint j, uint r) {
    float total = cube_face_totals[f];
    uint row = f * r + j;
    float row_total = cube_row_cdf[row * r + r - 1u];
    if (!(total > 0.0) || !(row_total > 0.0)) return 0.0;
    float row_below = j == 0u ? 0.0 : cube_face_cdf[row - 1u];
    float texel_below = i == 0u ? 0.0 : cube_row_cdf[row * r + i - 1u];
    return max(cube_face_cdf[row] - row_below, 0.0) / total *
           (max(cube_row_cdf[row * r + i] - texel_below, 0.0) / row_total);
}

// pdf_L(d | f) for the face f that d lies on (returned with it).
float cube_face_pdf(vec3 d, uint r, out uint f) {
    vec2 uv;
    f = cube_face_of(d, uv);
    uvec2 t = cube_texel(uv, r);
    float s = 2.0 / float(r);
    return cube_texel_probability(f, t.x, t.y, r) * cube_uv_to_solid_angle(uv, s * s);
}

// The first of the r entries of the face scan (rows) or a row scan (texels) from `begin`
// whose value exceeds x, stepped back over empty entries where x rounded up to the last value.
uint cube_search(bool rows, uint begin, uint r, float x) {
    uint lo = 0u;
    uint hi = r - 1u;
    while (lo < hi) {
        uint mid = (lo + hi) / 2u;
        float upper = rows ? cube_face_cdf[begin + mid] : cube_row_cdf[begin + mid];
        if (x < upper) hi = mid; else lo = mid + 1u;
    }
    while (lo > 0u) {
        float upper = rows ? cube_face_cdf[begin + lo] : cube_row_cdf[begin + lo];
        float lower = rows ? cube_face_cdf[begin + lo - 1u] : cube_row_cdf[begin + lo - 1u];
        if (upper > lower) break;
        --lo;
    }
    return lo;
}

#endif
