//! Counter-based pseudo-random numbers (docs/DESIGN.md "Sampling"): the PCG hash of Jarzynski
//! and Olano 2020, "Hash Functions for GPU Rendering", keyed by any number of u32 words.

/// PCG-RXS-M-XS hash of one word.
pub fn pcg_hash(v: u32) -> u32 {
    let state = v.wrapping_mul(747796405).wrapping_add(2891336453);
    let word = ((state >> ((state >> 28) + 4)) ^ state).wrapping_mul(277803737);
    (word >> 22) ^ word
}

/// Hash of several words (seed, pixel, sample, dimension, ...), chained.
pub fn hash(words: &[u32]) -> u32 {
    words.iter().fold(0x9e3779b9u32, |h, &w| pcg_hash(h ^ w))
}

/// Uniform in [0, 1) from the top 24 bits of a hash.
pub fn unit_f32(bits: u32) -> f32 {
    (bits >> 8) as f32 * (1.0 / (1u32 << 24) as f32)
}
