// Random numbers and warps shared by every kernel (CPU mirrors in src/sampling/).
// Pseudo-random: the PCG hash (Jarzynski and Olano 2020) keyed by (seed, pixel, sample,
// dimension), as src/sampling/pcg.rs. Quasi-random: Keller 97 Section 4.1 jittered Halton.
#ifndef SAMPLING_GLSL
#define SAMPLING_GLSL

const float PI = 3.14159265358979323846;
const float INV_PI = 0.31830988618379067154;

uint pcg_hash(uint v) {
    uint state = v * 747796405u + 2891336453u;
    uint word = ((state >> ((state >> 28u) + 4u)) ^ state) * 277803737u;
    return (word >> 22u) ^ word;
}

// Chained as src/sampling/pcg.rs `hash(&[a, b, c, d])`.
uint hash4(uint a, uint b, uint c, uint d) {
    uint h = 0x9e3779b9u;
    h = pcg_hash(h ^ a);
    h = pcg_hash(h ^ b);
    h = pcg_hash(h ^ c);
    h = pcg_hash(h ^ d);
    return h;
}

// Uniform in [0, 1) from the top 24 bits.
float unit_float(uint bits) {
    return float(bits >> 8u) * (1.0 / 16777216.0);
}

float random(uint seed, uint pixel, uint sample_index, uint dimension) {
    return unit_float(hash4(seed, pixel, sample_index, dimension));
}

// A 31-bit random integer: what discrete distributions (integer CDFs) are searched with.
uint random_u31(uint seed, uint pixel, uint sample_index, uint dimension) {
    return hash4(seed, pixel, sample_index, dimension) >> 1u;
}

float radical_inverse(uint base, uint i) {
    // Base 2 without a loop: the same value for i < 2^24 (and loops are costly: see
    // docs/code-layout.md "Kernels" on lavapipe's loop limit).
    if (base == 2u) return float(bitfieldReverse(i) >> 8u) * (1.0 / 16777216.0);
    float inv_base = 1.0 / float(base);
    float scale = inv_base;
    float result = 0.0;
    while (i > 0u) {
        result += float(i % base) * scale;
        i /= base;
        scale *= inv_base;
    }
    return result;
}

// Keller 97 Section 4.1's jittered low-discrepancy sampling, randomized by a Cranley-Patterson
// shift: point `index` of the Halton sequence in `base`, shifted by xi modulo 1. Each point is
// uniform (so any number of points is unbiased) and the set keeps the sequence's low
// discrepancy. (Jittering inside the cells of a b^n grid, as Keller does, covers the whole
// interval only when the point count is exactly b^n.)
float shifted_halton(uint base, uint index, float xi) {
    return min(fract(radical_inverse(base, index) + xi), 0.99999994);
}

// Orthonormal basis around a unit vector (Duff et al. 2017).
void basis(vec3 n, out vec3 t, out vec3 b) {
    float s = n.z >= 0.0 ? 1.0 : -1.0;
    float a = -1.0 / (s + n.z);
    float c = n.x * n.y * a;
    t = vec3(1.0 + s * n.x * n.x * a, s * c, -s * n.x);
    b = vec3(c, s + n.y * n.y * a, -n.y);
}

vec3 to_world(vec3 local, vec3 n) {
    vec3 t, b;
    basis(n, t, b);
    return local.x * t + local.y * b + local.z * n;
}

// Cosine-weighted hemisphere around +Z: pdf cos(theta) / pi.
vec3 sample_cosine_hemisphere(vec2 u) {
    float r = sqrt(u.x);
    float phi = 2.0 * PI * u.y;
    return vec3(r * cos(phi), r * sin(phi), sqrt(max(0.0, 1.0 - u.x)));
}

// Uniform barycentrics on a triangle (pbrt-v4 SampleUniformTriangle): (b1, b2).
vec2 sample_uniform_triangle(vec2 u) {
    float b0, b1;
    if (u.x < u.y) {
        b0 = u.x / 2.0;
        b1 = u.y - b0;
    } else {
        b1 = u.y / 2.0;
        b0 = u.x - b1;
    }
    return vec2(b1, 1.0 - b0 - b1);
}

float luminance(vec3 c) {
    return dot(c, vec3(0.2126, 0.7152, 0.0722));
}

// Veach's power heuristic (beta = 2) for one sample of each of two strategies.
// Written as 1 / (1 + (b/a)^2) so huge pdfs (grazing samples of tiny triangles) cannot make
// inf / inf.
float power_heuristic(float pdf_a, float pdf_b) {
    if (!(pdf_a > 0.0)) return 0.0;
    if (isinf(pdf_a)) return isinf(pdf_b) ? 0.5 : 1.0;
    float r = pdf_b / pdf_a;
    return 1.0 / (1.0 + r * r);
}

float infinity() {
    return uintBitsToFloat(0x7f800000u);
}

#endif
