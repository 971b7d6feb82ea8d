//! Inclusive prefix sums in f64: the reference the GPU scans (gpu::prefix_sum) are tested
//! against.

/// Inclusive scan of each row of `row_length` elements of `values`, in f64; returns the scans
/// and the row totals.
pub fn inclusive_scan_rows(values: &[f32], row_length: usize) -> (Vec<f64>, Vec<f64>) {
    let mut scanned = Vec::with_capacity(values.len());
    let mut totals = Vec::new();
    for row in values.chunks(row_length.max(1)) {
        let mut sum = 0.0f64;
        for &v in row {
            sum += v as f64;
            scanned.push(sum);
        }
        totals.push(sum);
    }
    (scanned, totals)
}

/// Largest |x - r| / |r| over elements (0 where both are 0).
pub fn max_relative_error(x: &[f32], reference: &[f64]) -> f64 {
    x.iter()
        .zip(reference)
        .map(|(&x, &r)| {
            let d = (x as f64 - r).abs();
            if d == 0.0 {
                0.0
            } else {
                d / r.abs()
            }
        })
        .fold(0.0, f64::max)
}

/// Random non-negative values shaped like the rows sampling tables scan: exponentially
/// distributed, one in 8 zero (texels with no light), one in 997 a spike 1000x larger (a sun).
/// Never constant; deterministic in `seed`.
pub fn cdf_like_values(seed: u32, n: usize) -> Vec<f32> {
    use super::pcg::{hash, unit_f32};
    (0..n as u32)
        .map(|i| {
            let h = hash(&[seed, i]);
            let u = unit_f32(hash(&[seed, i, 1]));
            let v = -(1.0 - u).ln();
            match h % 7976 {
                x if x % 8 == 0 => 0.0,
                x if x % 997 == 1 => v * 1000.0,
                _ => v,
            }
        })
        .collect()
}
