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

/// Uniform in [0, 1) for (seed, index, dimension): the CPU's own random streams (tests, the
/// scenes they build).
pub fn rand(seed: u32, index: u32, dim: u32) -> f32 {
    unit_f32(hash(&[seed, index, dim]))
}

/// Three of `rand`'s numbers, dimensions dim .. dim + 2.
pub fn rand3(seed: u32, index: u32, dim: u32) -> glam::Vec3 {
    glam::Vec3::new(
        rand(seed, index, dim),
        rand(seed, index, dim + 1),
        rand(seed, index, dim + 2),
    )
}

/// A uniform direction on the unit sphere from `rand`'s dimensions dim and dim + 1.
pub fn sphere_direction(seed: u32, index: u32, dim: u32) -> glam::Vec3 {
    let (u, v) = (rand(seed, index, dim), rand(seed, index, dim + 1));
    let z = 1.0 - 2.0 * u;
    let r = (1.0 - z * z).max(0.0).sqrt();
    let phi = 2.0 * std::f32::consts::PI * v;
    glam::Vec3::new(r * phi.cos(), r * phi.sin(), z)
}
