//! The GPU prefix sum against an f64 CPU scan: random non-negative rows (zeros and spikes
//! included, never constant) of many lengths, single and batched, within 1e-5 relative error
//! per element and per row total (src/gpu/prefix_sum.rs bounds it).

use crate::common;

use irad::gpu::{prefix_sum::PrefixSum, Buffer, Commands, Context, GpuError};
use irad::sampling::scan::{cdf_like_values, inclusive_scan_rows, max_relative_error};

const TOLERANCE: f64 = 1e-5;

fn check(ctx: &Context, row_length: usize, row_count: usize, seed: u32) {
    let n = row_length * row_count;
    let values = cdf_like_values(seed, n);
    let input = Buffer::from_slice(ctx, "values", &values).unwrap();
    let output = Buffer::<f32>::zeroed(ctx, "scanned", n).unwrap();
    let totals = Buffer::<f32>::zeroed(ctx, "row totals", row_count).unwrap();
    let scan = PrefixSum::new(ctx, row_length, row_count).unwrap();
    let mut cmd = Commands::new(ctx).unwrap();
    cmd.pass("scan", |cmd| scan.record(cmd, &input, &output, &totals))
        .unwrap();
    cmd.submit_and_wait().unwrap();

    let (expected, expected_totals) = inclusive_scan_rows(&values, row_length);
    let got = output.read().unwrap();
    let err = max_relative_error(&got, &expected);
    assert!(
        err <= TOLERANCE,
        "{row_length} x {row_count}: max relative error {err:e}"
    );
    let err = max_relative_error(&totals.read().unwrap(), &expected_totals);
    assert!(
        err <= TOLERANCE,
        "{row_length} x {row_count}: row totals relative error {err:e}"
    );
}

#[test]
fn single_rows_of_many_lengths() {
    common::with_gpu(|ctx| {
        // 1, around the invocation (16) and block (1024) sizes, non-powers of two, and lengths
        // needing two and three levels of block sums.
        for (i, &n) in [
            1, 2, 3, 15, 16, 17, 1000, 1023, 1024, 1025, 4097, 65_537, 1_048_577,
        ]
        .iter()
        .enumerate()
        {
            check(ctx, n, 1, i as u32);
        }
    });
}

#[test]
fn single_row_of_6_x_2_pow_20() {
    common::with_gpu(|ctx| check(ctx, 6 << 20, 1, 11));
}

#[test]
fn batched_6_x_1024_rows_of_1024() {
    common::with_gpu(|ctx| check(ctx, 1024, 6 * 1024, 12));
}

#[test]
fn batched_rows_of_odd_lengths() {
    common::with_gpu(|ctx| {
        check(ctx, 3001, 7, 13);
        check(ctx, 1, 5, 14);
        check(ctx, 2049, 33, 15);
    });
}

#[test]
fn one_plan_scans_new_data_in_later_submissions() {
    common::with_gpu(|ctx| {
        let n = 5000;
        let scan = PrefixSum::new(ctx, n, 1).unwrap();
        let output = Buffer::<f32>::zeroed(ctx, "scanned", n).unwrap();
        let totals = Buffer::<f32>::zeroed(ctx, "totals", 1).unwrap();
        for seed in 0..3 {
            let values = cdf_like_values(100 + seed, n);
            let input = Buffer::from_slice(ctx, "values", &values).unwrap();
            let mut cmd = Commands::new(ctx).unwrap();
            cmd.pass("scan", |cmd| scan.record(cmd, &input, &output, &totals))
                .unwrap();
            cmd.submit_and_wait().unwrap();
            let (expected, _) = inclusive_scan_rows(&values, n);
            assert!(max_relative_error(&output.read().unwrap(), &expected) <= TOLERANCE);
        }
    });
}

#[test]
fn mismatched_buffers_are_errors_naming_the_buffer() {
    common::with_gpu(|ctx| {
        let scan = PrefixSum::new(ctx, 100, 2).unwrap();
        let input = Buffer::<f32>::zeroed(ctx, "input", 200).unwrap();
        let short = Buffer::<f32>::zeroed(ctx, "short output", 150).unwrap();
        let totals = Buffer::<f32>::zeroed(ctx, "totals", 2).unwrap();
        let mut cmd = Commands::new(ctx).unwrap();
        let err = scan.record(&mut cmd, &input, &short, &totals).unwrap_err();
        assert!(
            matches!(&err, GpuError::BufferLength { name, expected: 200, given: 150 } if name == "short output"),
            "{err}"
        );
    });
}

#[test]
fn empty_rows_total_zero() {
    common::with_gpu(|ctx| {
        let scan = PrefixSum::new(ctx, 0, 3).unwrap();
        let none = Buffer::<f32>::zeroed(ctx, "no values", 0).unwrap();
        let out = Buffer::<f32>::zeroed(ctx, "no scan", 0).unwrap();
        let totals = Buffer::from_slice(ctx, "totals", &[5.0f32; 3]).unwrap();
        let mut cmd = Commands::new(ctx).unwrap();
        cmd.pass("scan", |cmd| scan.record(cmd, &none, &out, &totals))
            .unwrap();
        cmd.submit_and_wait().unwrap();
        assert_eq!(totals.read().unwrap(), [0.0; 3]);
    });
}

/// The device numbers subgroup lanes in invocation order, as the scans need (docs/DESIGN.md
/// "Subgroup widths"; src/gpu/subgroup_layout.rs). scripts/test.sh runs this at 8 and at 4 lanes.
#[test]
fn the_device_numbers_subgroup_lanes_in_invocation_order() {
    common::with_gpu(|ctx| {
        ctx.check_subgroup_layout().unwrap();
    });
}
