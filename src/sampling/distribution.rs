//! Discrete distributions with integer CDFs, built on the CPU in f64 and searched on the GPU
//! by `select_light` (lights.glsl) and `env_sample` (envmap.glsl); `sample` mirrors that search.
//!
//! A 31-bit random integer r picks the first entry with `r < upper[i]`. The probability that is
//! *realised* is therefore `(upper[i] - upper[i-1]) / 2^31`, exactly, and that (not the f64
//! weight ratio) is what `probabilities` holds and what every pdf divides by, on both the
//! light-sampling and the BSDF-sampling side of MIS: a float CDF searched with 24-bit random
//! numbers realises probabilities that differ from the weights for small entries, which biases
//! an estimator that divides by the weights (pbrt's and Mitsuba's float CDFs share that flaw).
//! An entry whose realised probability is 0 is never sampled and reports pdf 0, so the BSDF
//! side alone (with MIS weight 1) covers it.
//!
//! Static tables (light selection by power, the environment's texels) are built here once per
//! scene; per-pixel dynamic CDFs (Lu 14 Chapter 3) use the GPU prefix sum.

/// The integer scale of `upper`: random numbers are 31-bit.
pub const SCALE: f64 = (1u64 << 31) as f64;

#[derive(Clone, Debug)]
pub struct Distribution1D {
    /// Realised probabilities, `(upper[i] - upper[i-1]) / 2^31`.
    pub probabilities: Vec<f64>,
    /// Exclusive upper bounds of each entry's range of 31-bit integers; the last is 2^31.
    pub upper: Vec<u32>,
    /// The sum of the weights.
    pub total: f64,
}

impl Distribution1D {
    /// None when there is nothing to sample: no weights, a non-positive total, or a negative
    /// or non-finite weight.
    pub fn new(weights: &[f64]) -> Option<Distribution1D> {
        if weights.iter().any(|w| !w.is_finite() || *w < 0.0) {
            return None;
        }
        let total: f64 = weights.iter().sum();
        if weights.is_empty() || total <= 0.0 || !total.is_finite() {
            return None;
        }
        let mut running = 0.0f64;
        let mut upper: Vec<u32> = weights
            .iter()
            .map(|w| {
                running += w;
                ((running / total * SCALE).round() as u64).min(1 << 31) as u32
            })
            .collect();
        // From the last positive entry on, the bound is exactly 2^31: every r lands somewhere.
        let last_positive = weights.iter().rposition(|w| *w > 0.0).unwrap();
        for u in &mut upper[last_positive..] {
            *u = 1 << 31;
        }
        let probabilities = upper
            .iter()
            .scan(0u32, |previous, &u| {
                let p = (u - *previous) as f64 / SCALE;
                *previous = u;
                Some(p)
            })
            .collect();
        Some(Distribution1D {
            probabilities,
            upper,
            total,
        })
    }

    /// The index the GPU's search picks for a 31-bit `r`: the first with r < upper.
    pub fn sample(&self, r: u32) -> usize {
        self.upper.partition_point(|&u| u <= r)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn realised_probabilities_match_the_search_exactly() {
        let weights = [1.0, 0.0, 3.0, 1e-12, 0.0];
        let d = Distribution1D::new(&weights).unwrap();
        assert_eq!(d.probabilities.iter().sum::<f64>(), 1.0);
        assert_eq!(d.probabilities[1], 0.0);
        assert_eq!(d.probabilities[4], 0.0);
        // 1e-12 of 2^31 rounds to nothing: realised 0, never sampled.
        assert_eq!(d.probabilities[3], 0.0);
        assert!((d.probabilities[0] - 0.25).abs() < 1e-9);
        // The search boundaries are where the realised probabilities say.
        let first_of_2 = d.upper[1];
        assert_eq!(d.sample(first_of_2 - 1), 0);
        assert_eq!(d.sample(first_of_2), 2);
        assert_eq!(d.sample((1 << 31) - 1), 2);
        assert_eq!(d.sample(0), 0);
    }

    #[test]
    fn rejects_empty_and_bad_weights() {
        assert!(Distribution1D::new(&[]).is_none());
        assert!(Distribution1D::new(&[0.0, 0.0]).is_none());
        assert!(Distribution1D::new(&[1.0, f64::NAN]).is_none());
        assert!(Distribution1D::new(&[1.0, -1.0]).is_none());
    }
}
