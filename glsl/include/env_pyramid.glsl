// The `hierarchical` environment sampler of method `env` (Falcor's and Mitsuba 3's approach:
// a luminance mip pyramid descended 2x2 per level, no CDF), rebuilt on the GPU per frame
// (src/methods/envmap/pyramid.rs). Its leaves cover the sphere in the map's own
// parameterisation (u = phi / 2 pi, v = theta / pi) at H' = the power of two at or above the
// map's height and W' = 2 H'; each leaf weighs the largest luminance of the map texels its
// footprint touches (conservative: positive wherever the map is) times the leaf's exact
// solid angle (weigh_env_pyramid.comp). Level l + 1 sums level l's 2x2 blocks
// (reduce_env_pyramid.comp) up to the 2 x 1 top. A draw chooses one of the top two, then at
// every level the column of the 2x2 block by u.x and the row within it by u.y (each uniform
// rescaled), and places the direction uniformly in the leaf's solid angle, so the density is
// the leaf's weight over the total and over its solid angle. Needs scene.glsl and
// sampling.glsl; binding 26.
#ifndef ENV_PYRAMID_GLSL
#define ENV_PYRAMID_GLSL

// Every level in turn, finest first, each row-major.
layout(set = 0, binding = 26, std430) buffer EnvPyramid { float env_pyramid[]; };

// H': leaf rows.
uint pyramid_rows() {
    uint h = scene.env_size.y;
    return h <= 1u ? 1u : 1u << uint(findMSB(h - 1u) + 1);
}

// The number of levels, the 2 x 1 top included.
uint pyramid_levels() {
    return uint(findMSB(pyramid_rows())) + 1u;
}

// Where level l starts.
uint pyramid_offset(uint l) {
    uint rows = pyramid_rows();
    uint offset = 0u;
    for (uint k = 0u; k < l; ++k) offset += 2u * (rows >> k) * (rows >> k);
    return offset;
}

// The weight of texel (i, j) of level l, whose width is `width`.
float pyramid_weight(uint offset, uint width, uint i, uint j) {
    return env_pyramid[offset + j * width + i];
}

// Solid angle of a leaf in row j: (pi / H') (cos theta_j - cos theta_j+1), as a product of
// sines (no cancellation near the poles of tall maps).
float pyramid_leaf_solid_angle(uint j) {
    float h = float(pyramid_rows());
    return PI / h * 2.0 * sin(PI * (float(j) + 0.5) / h) * sin(0.5 * PI / h);
}

float pyramid_total() {
    uint top = pyramid_offset(pyramid_levels() - 1u);
    return env_pyramid[top] + env_pyramid[top + 1u];
}

// The density of a leaf (its weight over the total and its solid angle).
float pyramid_leaf_density(uint i, uint j) {
    float total = pyramid_total();
    if (!(total > 0.0)) return 0.0;
    uint rows = pyramid_rows();
    float omega = pyramid_leaf_solid_angle(j);
    return omega > 0.0 ? env_pyramid[j * 2u * rows + i] / total / omega : 0.0;
}

// The density of direction d.
float pyramid_density(vec3 d) {
    uint rows = pyramid_rows();
    float u = fract(atan(d.x, -d.z) * (0.5 * INV_PI));
    float v = acos(clamp(d.y, -1.0, 1.0)) * INV_PI;
    uint i = min(uint(u * float(2u * rows)), 2u * rows - 1u);
    uint j = min(uint(v * float(rows)), rows - 1u);
    return pyramid_leaf_density(i, j);
}

// Splits x in [0, 1) between weights a and b: true for b; x rescaled to [0, 1) within it. A
// side of weight zero is never chosen.
bool pyramid_split(float a, float b, inout float x) {
    float t = x * (a + b);
    if (b > 0.0 && (t >= a || !(a > 0.0))) {
        x = clamp((t - a) / b, 0.0, 0.99999994);
        return true;
    }
    x = a > 0.0 ? clamp(t / a, 0.0, 0.99999994) : 0.0;
    return false;
}

// Draws a direction: u.xy descend the pyramid, u.zw place it in the leaf; returns false
// (and nothing) for an all-black map. `density` is the leaf's density.
bool pyramid_sample(vec4 u, out vec3 d, out float density) {
    d = vec3(0.0, 1.0, 0.0);
    density = 0.0;
    uint levels = pyramid_levels();
    uint l = levels - 1u;
    uint offset = pyramid_offset(l);
    if (!(env_pyramid[offset] + env_pyramid[offset + 1u] > 0.0)) return false;
    vec2 x = u.xy;
    uint i = pyramid_split(env_pyramid[offset], env_pyramid[offset + 1u], x.x) ? 1u : 0u;
    uint j = 0u;
    uint rows = pyramid_rows();
    while (l > 0u) {
        --l;
        uint width = 2u * (rows >> l);
        offset = pyramid_offset(l);
        i *= 2u;
        j *= 2u;
        float v00 = pyramid_weight(offset, width, i, j);
        float v10 = pyramid_weight(offset, width, i + 1u, j);
        float v01 = pyramid_weight(offset, width, i, j + 1u);
        float v11 = pyramid_weight(offset, width, i + 1u, j + 1u);
        if (pyramid_split(v00 + v01, v10 + v11, x.x)) {
            i += 1u;
            if (pyramid_split(v10, v11, x.y)) j += 1u;
        } else if (pyramid_split(v00, v01, x.y)) {
            j += 1u;
        }
    }
    float phi = 2.0 * PI * (float(i) + u.z) / float(2u * rows);
    float cos_top = cos(PI * float(j) / float(rows));
    float cos_bottom = cos(PI * float(j + 1u) / float(rows));
    float y = mix(cos_top, cos_bottom, u.w);
    float radius = sqrt(max(0.0, 1.0 - y * y));
    d = vec3(radius * sin(phi), y, -radius * cos(phi));
    density = pyramid_leaf_density(i, j);
    return density > 0.0;
}

#endif
