//! Discrete distributions built on the CPU in f64 and stored as f32 inclusive CDFs, searched on
//! the GPU by `select_light` (lights.glsl) and `env_sample` (envmap.glsl); `sample` mirrors
//! that binary search.
//!
//! Static tables (light selection by power, the environment's texel CDF) are built here once
//! per scene, in f64, rather than with the GPU prefix sum: the pdfs the kernels divide by must
//! match what they sample, and an f64 build makes the f32 CDF exact to rounding. Per-pixel
//! dynamic CDFs (Lu 14 Chapter 3) use the GPU prefix sum.

#[derive(Clone, Debug)]
pub struct Distribution1D {
    /// Normalized probabilities, in f64.
    pub probabilities: Vec<f64>,
    /// Inclusive running sums of `probabilities` as f32, the last exactly 1.
    pub cdf: Vec<f32>,
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
        if weights.is_empty() || !(total > 0.0) || !total.is_finite() {
            return None;
        }
        let probabilities: Vec<f64> = weights.iter().map(|w| w / total).collect();
        let mut running = 0.0f64;
        let mut cdf: Vec<f32> = probabilities
            .iter()
            .map(|p| {
                running += p;
                running as f32
            })
            .collect();
        // Entries after the last positive one stay at exactly 1 so they are never chosen.
        let last_positive = weights.iter().rposition(|w| *w > 0.0).unwrap();
        for c in &mut cdf[last_positive..] {
            *c = 1.0;
        }
        Some(Distribution1D {
            probabilities,
            cdf,
            total,
        })
    }

    /// The index the GPU's binary search picks for `u` in [0, 1): the first with u < cdf.
    pub fn sample(&self, u: f32) -> usize {
        let (mut lo, mut hi) = (0usize, self.cdf.len() - 1);
        while lo < hi {
            let mid = (lo + hi) / 2;
            if u < self.cdf[mid] {
                hi = mid;
            } else {
                lo = mid + 1;
            }
        }
        lo
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn samples_in_proportion_to_weights() {
        let d = Distribution1D::new(&[1.0, 0.0, 3.0, 0.0]).unwrap();
        let n = 100_000;
        let mut counts = [0usize; 4];
        for i in 0..n {
            counts[d.sample((i as f32 + 0.5) / n as f32)] += 1;
        }
        assert_eq!(counts[1], 0);
        assert_eq!(counts[3], 0);
        assert!((counts[0] as f64 / n as f64 - 0.25).abs() < 1e-3);
        assert_eq!(*d.cdf.last().unwrap(), 1.0);
    }

    #[test]
    fn rejects_empty_and_bad_weights() {
        assert!(Distribution1D::new(&[]).is_none());
        assert!(Distribution1D::new(&[0.0, 0.0]).is_none());
        assert!(Distribution1D::new(&[1.0, f64::NAN]).is_none());
        assert!(Distribution1D::new(&[1.0, -1.0]).is_none());
    }
}
