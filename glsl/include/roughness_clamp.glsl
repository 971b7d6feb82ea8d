// Tokuyoshi 12 Section 5: glossy spike suppression by clamping roughness. The Phong lobe is
// read as a kernel over directions, (n + 1) / (2 pi) cos^n, whose peak may not exceed the
// density of the samples around it divided by m (Eq. 9), which bounds the exponent per sample:
// n_i = max(0, min(n, 2 pi d / m - 1)) (Eq. 10). m = m' f cos / D (the lobe's weight with D
// cancelled: m' Ks (n + 2) / (n + 1) cos for irad's normalized Phong), m' = 16 in the paper.
// irad's lobe is centred on the mirror direction rather than on the half vector, so the
// kernel lives in the space of reflected directions. Needs scene.glsl and sampling.glsl.
#ifndef ROUGHNESS_CLAMP_GLSL
#define ROUGHNESS_CLAMP_GLSL

// `m` with its Phong exponent clamped for samples of solid-angle density `density`; `cos_in`
// is the cosine of the incident direction at the surface, m_prime the paper's m'.
Material clamp_roughness(Material m, float density, float cos_in, float m_prime) {
    float ks = max(max(m.ks.r, m.ks.g), m.ks.b);
    float exponent = m.ks.w;
    float neighbours = m_prime * ks * (exponent + 2.0) / (exponent + 1.0) * max(cos_in, 0.0);
    if (neighbours <= 0.0 || !(density < uintBitsToFloat(0x7f800000u))) return m;
    m.ks.w = max(0.0, min(exponent, 2.0 * PI * density / neighbours - 1.0));
    return m;
}

// Eq. 13 and 17: the density at a vertex from those of its two edges, 1 / d = 1 / d_in +
// 1 / d_out (the kernel radii add in quadrature); an infinite one (a pinhole camera's edge, a
// point light's) leaves the other.
float combine_densities(float d_in, float d_out) {
    return d_in * d_out / (d_in + d_out);
}

#endif
