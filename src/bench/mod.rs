//! Benchmarks: they measure and print; they assert nothing (tests do).

pub mod chart;
pub mod env;
pub mod ir;
pub mod lightfield;
pub mod rays;
pub mod scan;
pub mod suite;

/// Median of a non-empty list.
pub fn median(values: &mut [f64]) -> f64 {
    values.sort_by(|a, b| a.total_cmp(b));
    let n = values.len();
    if n % 2 == 1 {
        values[n / 2]
    } else {
        0.5 * (values[n / 2 - 1] + values[n / 2])
    }
}
