// Cube maps for environment sampling (docs/DESIGN.md "Conventions"; Lu 14 Section 3.3): faces
// +X, -X, +Y, -Y, +Z, -Z (0..5), face coordinates (u, v) in [-1, 1], a face of R x R texels,
// texel (i, j) covering u in [-1 + 2i/R, -1 + 2(i+1)/R] and v likewise in j, index
// face R^2 + j R + i. src/sampling/cubemap.rs mirrors every function here.
#ifndef CUBEMAP_GLSL
#define CUBEMAP_GLSL

// The unnormalized direction of (u, v) on face f.
vec3 cube_face_point(uint f, float u, float v) {
    if (f == 0u) return vec3(1.0, -v, -u);
    if (f == 1u) return vec3(-1.0, -v, u);
    if (f == 2u) return vec3(u, 1.0, v);
    if (f == 3u) return vec3(u, -1.0, -v);
    if (f == 4u) return vec3(u, -v, 1.0);
    return vec3(-u, -v, -1.0);
}

// The face of d (its major axis; ties in the order x, y, z) and d's face coordinates.
uint cube_face_of(vec3 d, out vec2 uv) {
    vec3 a = abs(d);
    if (a.x >= a.y && a.x >= a.z) {
        uv = d.x > 0.0 ? vec2(-d.z, -d.y) / a.x : vec2(d.z, -d.y) / a.x;
        return d.x > 0.0 ? 0u : 1u;
    }
    if (a.y >= a.z) {
        uv = d.y > 0.0 ? vec2(d.x, d.z) / a.y : vec2(d.x, -d.z) / a.y;
        return d.y > 0.0 ? 2u : 3u;
    }
    uv = d.z > 0.0 ? vec2(d.x, -d.y) / a.z : vec2(-d.x, -d.y) / a.z;
    return d.z > 0.0 ? 4u : 5u;
}

// The texel of face coordinates uv on a face of resolution r: (i, j).
uvec2 cube_texel(vec2 uv, uint r) {
    uvec2 t = uvec2(clamp((uv + 1.0) * 0.5 * float(r), vec2(0.0), vec2(float(r) - 0.5)));
    return min(t, uvec2(r - 1u));
}

// The solid angle of texel (i, j): the integral of (1 + u^2 + v^2)^(-3/2) over it, by 3 x 3
// Gauss-Legendre (relative error below 1e-5 from R = 4 up; the closed form, a second
// difference of atan(u v / sqrt(1 + u^2 + v^2)), cancels catastrophically in f32 at large R,
// where src/sampling/cubemap.rs evaluates it in f64).
float cube_texel_solid_angle(uint r, uint i, uint j) {
    const float x[3] = float[](-0.7745966692414834, 0.0, 0.7745966692414834);
    const float wt[3] = float[](0.5555555555555556, 0.8888888888888888, 0.5555555555555556);
    float h = 1.0 / float(r);  // half the texel's side
    vec2 c = vec2(-1.0 + h * (2.0 * float(i) + 1.0), -1.0 + h * (2.0 * float(j) + 1.0));
    float sum = 0.0;
    for (int a = 0; a < 3; ++a) {
        for (int b = 0; b < 3; ++b) {
            vec2 uv = c + h * vec2(x[a], x[b]);
            float q = 1.0 + dot(uv, uv);
            sum += wt[a] * wt[b] / (q * sqrt(q));
        }
    }
    return sum * h * h;
}

// The solid-angle density of a direction placed uniformly in (u, v) over a region of area
// `area` in (u, v): (1 + u^2 + v^2)^(3/2) / area.
float cube_uv_to_solid_angle(vec2 uv, float area) {
    float q = 1.0 + dot(uv, uv);
    return q * sqrt(q) / area;
}

#endif
