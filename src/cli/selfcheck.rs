//! `irad selfcheck`: runs the GPU prefix sum on random rows and compares it with an f64 CPU
//! scan, so a newcomer sees at once that the device computes what irad expects.

use anyhow::Result;

use irad::gpu::{prefix_sum::PrefixSum, Buffer, Commands, Context};
use irad::sampling::scan::{cdf_like_values, inclusive_scan_rows, max_relative_error};

/// Largest relative error per element accepted: the f32 scan's worst case, about 1e-5 at 2^22
/// elements (src/gpu/prefix_sum.rs).
pub const SCAN_TOLERANCE: f64 = 1e-5;

pub struct ScanCheck {
    pub row_length: usize,
    pub row_count: usize,
    pub max_relative_error: f64,
    pub max_total_error: f64,
}

impl ScanCheck {
    pub fn passed(&self) -> bool {
        self.max_relative_error <= SCAN_TOLERANCE && self.max_total_error <= SCAN_TOLERANCE
    }
}

/// Scans `row_count` rows of `row_length` random values on the GPU and measures the error
/// against the f64 scan.
pub fn check_scan(
    ctx: &Context,
    row_length: usize,
    row_count: usize,
    seed: u32,
) -> Result<ScanCheck> {
    let n = row_length * row_count;
    let values = cdf_like_values(seed, n);
    let input = Buffer::from_slice(ctx, "selfcheck input", &values)?;
    let output = Buffer::<f32>::zeroed(ctx, "selfcheck scan", n)?;
    let totals = Buffer::<f32>::zeroed(ctx, "selfcheck row totals", row_count)?;
    let scan = PrefixSum::new(ctx, row_length, row_count)?;
    let mut cmd = Commands::new(ctx)?;
    cmd.pass("prefix sum", |cmd| {
        scan.record(cmd, &input, &output, &totals)
    })?;
    cmd.submit_and_wait()?;
    let (expected, expected_totals) = inclusive_scan_rows(&values, row_length);
    Ok(ScanCheck {
        row_length,
        row_count,
        max_relative_error: max_relative_error(&output.read()?, &expected),
        max_total_error: max_relative_error(&totals.read()?, &expected_totals),
    })
}

/// The self-check's cases: one element, a non-power of two, a long row, many rows.
pub const SCAN_CASES: &[(usize, usize)] = &[(1, 1), (1000, 1), (3 << 20, 1), (1024, 6 * 1024)];
