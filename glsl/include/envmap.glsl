// The environment map (docs/DESIGN.md "Conventions"): equirectangular, piecewise constant over
// texels, u = frac(atan2(x, -z) / 2 pi), v = acos(y) / pi, row 0 at +Y. Importance sampled
// by texel in proportion to luminance times solid angle (EnvCdf, an integer CDF built on the
// CPU, src/sampling/distribution.rs), then uniformly in solid angle within the texel, so the
// pdf is the texel's realised probability over its solid angle (EnvTexels .w), exactly.
#ifndef ENVMAP_GLSL
#define ENVMAP_GLSL

#include "sampling.glsl"
#include "scene.glsl"

uint env_texel_index(vec3 d) {
    uint w = scene.env_size.x;
    uint h = scene.env_size.y;
    float u = fract(atan(d.x, -d.z) * (0.5 * INV_PI));
    float v = acos(clamp(d.y, -1.0, 1.0)) * INV_PI;
    uint i = min(uint(u * float(w)), w - 1u);
    uint j = min(uint(v * float(h)), h - 1u);
    return j * w + i;
}

// Solid angle of any texel in row j: (2 pi / W) (cos theta_top - cos theta_bottom).
float env_texel_solid_angle(uint j) {
    float h = float(scene.env_size.y);
    return 2.0 * PI / float(scene.env_size.x) * (cos(PI * float(j) / h) - cos(PI * float(j + 1u) / h));
}

vec3 env_radiance(vec3 d) {
    if (scene.env_size.z == 0u) return vec3(0.0);
    return env_texels[env_texel_index(d)].rgb;
}

// Solid-angle pdf of env_sample, before light selection.
float env_pdf(vec3 d) {
    if (scene.env_size.z == 0u) return 0.0;
    return env_texels[env_texel_index(d)].w;
}

// Samples a direction: texel by binary search over the CDF, then uniform in the texel's
// solid angle (phi uniform, cos(theta) uniform between the row's edges). Returns the texel's
// radiance with it, so rounding at a texel edge cannot pair one texel's pdf with another's L.
// r: a 31-bit random integer picks the texel; u places the direction in it.
vec3 env_sample(uint r, vec2 u, out vec3 radiance, out float pdf) {
    uint w = scene.env_size.x;
    uint h = scene.env_size.y;
    uint lo = 0u;
    uint hi = w * h - 1u;
    while (lo < hi) {
        uint mid = (lo + hi) / 2u;
        if (r < env_cdf[mid]) hi = mid; else lo = mid + 1u;
    }
    uint i = lo % w;
    uint j = lo / w;
    float phi = 2.0 * PI * (float(i) + u.x) / float(w);
    float cos_top = cos(PI * float(j) / float(h));
    float cos_bottom = cos(PI * float(j + 1u) / float(h));
    float y = mix(cos_top, cos_bottom, u.y);
    float radius = sqrt(max(0.0, 1.0 - y * y));
    vec3 d = vec3(radius * sin(phi), y, -radius * cos(phi));
    radiance = env_texels[lo].rgb;
    pdf = env_texels[lo].w;
    return d;
}

#endif
