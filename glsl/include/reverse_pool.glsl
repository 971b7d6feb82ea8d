// bir's pool of camera points (Segovia 06 Section 3.1): the M G-buffer texels at pseudo-random
// pixels that a batch's reverse VPLs start from, and Eq. 7's density over them. Shared by
// trace_reverse_vpls.comp (the density of each reverse VPL) and find_uncovered_vpls.comp
// (which standard VPLs no reverse VPL could have landed on). Needs bvh.glsl, sampling.glsl
// and gbuffer.glsl.
#ifndef REVERSE_POOL_GLSL
#define REVERSE_POOL_GLSL

// Pool point m: position, shading normal and geometric normal on the camera's side; false
// when its camera ray missed the scene. Pixel m is pcg(seed, m) mod the pixel count.
bool pool_point(uint seed, uint pixels, uint m, out vec3 x, out vec3 n, out vec3 side) {
    uint pixel = pcg_hash(seed ^ pcg_hash(m + 0x9e3779b9u)) % pixels;
    GBufferTexel g = gbuffer[pixel];
    x = g.position.xyz;
    vec3 wo;
    return gbuffer_surface(g, wo, side, n);
}

// Eq. 7 over the pool: the mean over pool points x1 of p(x1 -> x2) = cos(theta_1) / pi *
// cos(theta_2) / d^2 * V(x1, x2), for x2 on a surface with geometric normal ng2 whose emitting
// side is side2 (only pool points on that side count) and origin2 = x2 off that side: the
// share of pool points [begin, end) in it (a shadow ray each, so kernels split the pool over
// dispatches: docs/DESIGN.md "The loop budget"). With `first`, returns at the first pool point that reaches x2
// (a positive value, not the density).
float pool_density(uint seed, uint pixels, uint pool, uint begin, uint end, vec3 x2, vec3 ng2,
                   vec3 side2, vec3 origin2, bool first) {
    float density = 0.0;
    for (uint m = begin; m < min(end, pool); ++m) {
        vec3 xm, nm, sidem;
        if (!pool_point(seed, pixels, m, xm, nm, sidem)) continue;
        vec3 d = x2 - xm;
        float dist2 = dot(d, d);
        if (dist2 <= 0.0) continue;
        vec3 wm = d * inversesqrt(dist2);
        float cos1 = dot(nm, wm);
        float cos2 = abs(dot(ng2, wm));
        if (cos1 <= 0.0 || dot(sidem, wm) <= 0.0 || cos2 <= 0.0) continue;
        // Visible from the same side the VPL emits on.
        if (dot(side2, -wm) <= 0.0) continue;
        vec3 om = offset_origin(xm, sidem);
        if (trace_any(om, origin2 - om, 0.9999)) continue;
        density += cos1 * INV_PI * cos2 / dist2;
        if (first) return density;
    }
    return density / float(max(pool, 1u));
}

#endif
