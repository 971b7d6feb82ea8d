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

float radical_inverse(uint base, uint i) {
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

// Keller 97 Section 4.1: point `index` of the Halton sequence in `base`, jittered inside its
// cell of the b^n grid, where b^n >= count: Phi_b(i) + xi / b^n. For count <= b^n the points
// 0..count-1 fall in distinct cells, so the set stays stratified.
float jittered_halton(uint base, uint index, uint count, float xi) {
    float cell = 1.0;
    uint reach = 1u;
    while (reach < count) {
        reach *= base;
        cell /= float(base);
    }
    return min(radical_inverse(base, index) + xi * cell, 0.99999994);
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
float power_heuristic(float pdf_a, float pdf_b) {
    float a = pdf_a * pdf_a;
    float b = pdf_b * pdf_b;
    return a + b > 0.0 ? a / (a + b) : 0.0;
}

float infinity() {
    return uintBitsToFloat(0x7f800000u);
}

#endif
