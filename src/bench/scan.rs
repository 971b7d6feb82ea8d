//! `irad bench scan`: prefix-sum throughput next to a plain copy kernel's, measured in the same
//! run on the same buffers, the copy being the memory-bandwidth bound.
//!
//! GB/s counts 8 bytes per element for both (one f32 read, one f32 written): the least traffic
//! either can do, so the two figures compare elements per second.

use anyhow::Result;

use super::median;
use crate::gpu::{copy::CopyValues, prefix_sum::PrefixSum, Buffer, Commands, Context};
use crate::sampling::scan::cdf_like_values;

#[derive(Clone, Copy, Debug)]
pub struct ScanCase {
    pub row_length: usize,
    pub row_count: usize,
}

impl ScanCase {
    pub fn elements(&self) -> usize {
        self.row_length * self.row_count
    }
}

/// Default cases: single rows from small to 6 x 2^20, and the batched form (6 x 1024 rows of
/// 1024, a cube map's conditional CDFs).
pub const DEFAULT_CASES: &[ScanCase] = &[
    ScanCase {
        row_length: 1 << 16,
        row_count: 1,
    },
    ScanCase {
        row_length: 1_000_000,
        row_count: 1,
    },
    ScanCase {
        row_length: 1 << 22,
        row_count: 1,
    },
    ScanCase {
        row_length: 6 << 20,
        row_count: 1,
    },
    ScanCase {
        row_length: 1024,
        row_count: 1024,
    },
    ScanCase {
        row_length: 1024,
        row_count: 6 * 1024,
    },
];

pub struct ScanResult {
    pub case: ScanCase,
    pub dispatches: usize,
    pub scan_ms: f64,
    pub copy_ms: f64,
}

impl ScanResult {
    pub fn scan_gbps(&self) -> f64 {
        gbps(self.case.elements(), self.scan_ms)
    }
    pub fn copy_gbps(&self) -> f64 {
        gbps(self.case.elements(), self.copy_ms)
    }
}

fn gbps(elements: usize, ms: f64) -> f64 {
    8.0 * elements as f64 / (ms * 1e6)
}

/// Median GPU times of `repeats` scans and copies of `case` after `warmup` of each.
pub fn run_case(
    ctx: &Context,
    case: ScanCase,
    warmup: usize,
    repeats: usize,
) -> Result<ScanResult> {
    let n = case.elements();
    anyhow::ensure!(
        n % 4 == 0,
        "bench scan: {n} elements is not a multiple of 4 (the copy kernel moves vec4s)"
    );
    // Device-side sizes are checked (against the device's limits) before any host data is made.
    let scan = PrefixSum::new(ctx, case.row_length, case.row_count)?;
    let output = Buffer::<f32>::zeroed(ctx, "bench output", n)?;
    let totals = Buffer::<f32>::zeroed(ctx, "bench row totals", case.row_count)?;
    let input = Buffer::from_slice(ctx, "bench input", &cdf_like_values(7, n))?;
    let copy = CopyValues::new(ctx)?;
    let (mut scan_ms, mut copy_ms) = (Vec::new(), Vec::new());
    for i in 0..warmup + repeats {
        let mut cmd = Commands::new(ctx)?;
        cmd.pass("scan", |cmd| scan.record(cmd, &input, &output, &totals))?;
        cmd.pass("copy", |cmd| copy.record(cmd, &input, &output))?;
        let t = cmd.submit_and_wait()?;
        if i >= warmup {
            let wall = t.wall_ms;
            scan_ms.push(t.gpu_ms("scan").unwrap_or(wall));
            copy_ms.push(t.gpu_ms("copy").unwrap_or(wall));
        }
    }
    Ok(ScanResult {
        case,
        dispatches: scan.dispatch_count(),
        scan_ms: median(&mut scan_ms),
        copy_ms: median(&mut copy_ms),
    })
}

pub fn print_table(device: &str, results: &[ScanResult]) {
    println!("prefix sum vs copy on {device} (GB/s = 8 bytes per element / median GPU time)");
    println!(
        "{:>10} {:>6} {:>10} {:>4} {:>10} {:>9} {:>10} {:>9} {:>10}",
        "row",
        "rows",
        "elements",
        "disp",
        "scan ms",
        "scan GB/s",
        "copy ms",
        "copy GB/s",
        "scan/copy"
    );
    for r in results {
        println!(
            "{:>10} {:>6} {:>10} {:>4} {:>10.3} {:>9.2} {:>10.3} {:>9.2} {:>9.2}x",
            r.case.row_length,
            r.case.row_count,
            r.case.elements(),
            r.dispatches,
            r.scan_ms,
            r.scan_gbps(),
            r.copy_ms,
            r.copy_gbps(),
            r.scan_ms / r.copy_ms
        );
    }
    println!("target: scan time within 3x of copy time (scan/copy <= 3)");
}
