// Scrambled Halton points (Keller 97 Section 3; IR slides: "apply a random permutation on the
// digits of n ... (scrambled Halton)"): dimension k uses the k-th prime as base, and each
// digit level of each dimension gets its own random digit shift, keyed by the seed. Digit
// shifts are a random permutation of the digits, so every point stays uniform (the estimators
// stay unbiased) and a segment of the sequence keeps its low discrepancy, while the
// correlations between high-dimensional Halton components (IR slides: "degradation after 14
// dimensions") are broken up. No CPU mirror: tests judge its points by the distributions
// they draw (tests/env.rs, tests/lightfield.rs).
#ifndef HALTON_GLSL
#define HALTON_GLSL

#include "sampling.glsl"

#define HALTON_DIMENSIONS 128u

const uint HALTON_PRIMES[128] = uint[](
    2u, 3u, 5u, 7u, 11u, 13u, 17u, 19u, 23u, 29u, 31u, 37u, 41u, 43u, 47u, 53u,
    59u, 61u, 67u, 71u, 73u, 79u, 83u, 89u, 97u, 101u, 103u, 107u, 109u, 113u, 127u, 131u,
    137u, 139u, 149u, 151u, 157u, 163u, 167u, 173u, 179u, 181u, 191u, 193u, 197u, 199u, 211u, 223u,
    227u, 229u, 233u, 239u, 241u, 251u, 257u, 263u, 269u, 271u, 277u, 281u, 283u, 293u, 307u, 311u,
    313u, 317u, 331u, 337u, 347u, 349u, 353u, 359u, 367u, 373u, 379u, 383u, 389u, 397u, 401u, 409u,
    419u, 421u, 431u, 433u, 439u, 443u, 449u, 457u, 461u, 463u, 467u, 479u, 487u, 491u, 499u, 503u,
    509u, 521u, 523u, 541u, 547u, 557u, 563u, 569u, 571u, 577u, 587u, 593u, 599u, 601u, 607u, 613u,
    617u, 619u, 631u, 641u, 643u, 647u, 653u, 659u, 661u, 673u, 677u, 683u, 691u, 701u, 709u, 719u);

// Component `dimension` of scrambled Halton point `index`; digit levels down to 2^-24.
float halton(uint dimension, uint index, uint seed) {
    uint base = HALTON_PRIMES[min(dimension, HALTON_DIMENSIONS - 1u)];
    float inv_base = 1.0 / float(base);
    float scale = inv_base;
    float result = 0.0;
    uint level = 0u;
    while (scale > 5.9604645e-8) {
        uint digit = index % base;
        index /= base;
        uint shift = hash4(seed, dimension, level, 0x68616c74u) % base;
        result += float((digit + shift) % base) * scale;
        scale *= inv_base;
        level += 1u;
    }
    return min(result, 0.99999994);
}

#endif
