//! Inclusive prefix sum of f32 on the GPU, for one row of any length or many rows at once (with
//! each row's total): the CDF builder every sampling table in irad uses.
//!
//! Reduce-then-scan: `reduce_blocks` sums each block of SCAN_BLOCK = 64 x 16 elements, the
//! block sums are scanned by the same plan one level up (recursively, until a row is one
//! block), and `scan_blocks` scans each block and adds the scanned sum of the blocks before it.
//! Traffic is 2 reads and 1 write per element, against 1 and 1 for a copy.
//!
//! Precision: f32 rounding error grows with the length of the longest chain of sequential
//! additions, so no element is ever a long running sum. Each invocation adds at most 16
//! elements in sequence, subgroups and workgroups combine those as a tree, and the block
//! offsets come from the same scheme one level up, so the chain behind any element has
//! O(16 + log2(n)) additions: for non-negative data the relative error stays near
//! (16 + 3 log2 n) * 2^-24, about 1e-5 worst case at n = 2^22 and well below it in practice
//! (tests/prefix_sum.rs measures it against an f64 scan).

use bytemuck::{Pod, Zeroable};

use super::buffer::{Buffer, GpuBuffer};
use super::commands::Commands;
use super::context::Context;
use super::error::{GpuError, GpuResult};
use super::kernel::{bind, Kernel};

/// SCAN_ITEMS of glsl/include/scan_layout.glsl: consecutive elements per invocation.
const ITEMS_PER_INVOCATION: u32 = 16;

/// Push constants of both scan kernels (ScanParams in scan_layout.glsl).
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
struct ScanParams {
    row_length: u32,
    row_count: u32,
    blocks_per_row: u32,
    _pad: u32,
}

/// The GLSL layouts the structs above mirror (src/gpu/contracts.rs checks them).
#[cfg(test)]
pub(crate) const GPU_LAYOUTS: &[crate::gpu::contracts::GpuLayout] = {
    use crate::gpu::contracts::gpu_layout;
    &[gpu_layout!(ScanParams in ["scan_blocks", "reduce_blocks"] {
        row_length,
        row_count,
        blocks_per_row,
        _pad,
    })]
};

/// glsl/gpu/reduce_blocks.comp: the sum of every block of every row.
pub struct ReduceBlocks(Kernel);

impl ReduceBlocks {
    pub fn new(ctx: &Context) -> GpuResult<Self> {
        Ok(ReduceBlocks(Kernel::new(ctx, "reduce_blocks")?))
    }

    fn record<'a>(
        &'a self,
        cmd: &mut Commands<'a>,
        values: &'a Buffer<f32>,
        block_sums: &'a Buffer<f32>,
        p: ScanParams,
    ) -> GpuResult<()> {
        let groups = grid(p.row_count * p.blocks_per_row);
        self.0.dispatch(
            cmd,
            &[bind("Values", values), bind("BlockSums", block_sums)],
            &p,
            groups,
        )
    }
}

/// glsl/gpu/scan_blocks.comp: the scan of every block, offset by the blocks before it.
pub struct ScanBlocks(Kernel);

impl ScanBlocks {
    pub fn new(ctx: &Context) -> GpuResult<Self> {
        Ok(ScanBlocks(Kernel::new(ctx, "scan_blocks")?))
    }

    fn record<'a>(
        &'a self,
        cmd: &mut Commands<'a>,
        values: &'a Buffer<f32>,
        block_offsets: &'a Buffer<f32>,
        scanned: &'a Buffer<f32>,
        row_totals: &'a Buffer<f32>,
        p: ScanParams,
    ) -> GpuResult<()> {
        let groups = grid(p.row_count * p.blocks_per_row);
        let bindings = [
            bind("Values", values),
            bind("BlockOffsets", block_offsets),
            bind("Scanned", scanned),
            bind("RowTotals", row_totals),
        ];
        self.0.dispatch(cmd, &bindings, &p, groups)
    }
}

/// Workgroups for `blocks` blocks on a 2D grid: long rows and many rows both fit in
/// maxComputeWorkGroupCount (65535 guaranteed in x and y).
fn grid(blocks: u32) -> [u32; 3] {
    let x = blocks.clamp(1, 65535);
    [x, blocks.div_ceil(x).max(1), 1]
}

/// One level of the recursion: rows of `row_length` cut into `blocks_per_row` blocks; when a
/// row has several blocks, their sums and the scan of those sums.
struct Level {
    row_length: u32,
    blocks_per_row: u32,
    sums: Option<(Buffer<f32>, Buffer<f32>)>,
}

/// A prefix sum of `row_count` rows of `row_length` floats, with its scratch buffers (sized once,
/// O(n / 1024)); record it into any number of submissions.
pub struct PrefixSum {
    reduce: ReduceBlocks,
    scan: ScanBlocks,
    row_length: u32,
    row_count: u32,
    levels: Vec<Level>,
    inner_totals: Buffer<f32>,
    unused_offsets: Buffer<f32>,
}

impl PrefixSum {
    pub fn new(ctx: &Context, row_length: usize, row_count: usize) -> GpuResult<Self> {
        let too_long = |what: &str| GpuError::BufferTooLarge {
            name: format!("prefix sum {what}"),
            bytes: (row_length as u64)
                .saturating_mul(row_count as u64)
                .saturating_mul(4),
            limit_name: "u32 element indexing",
            limit: u32::MAX as u64,
        };
        let row_length_u32 = u32::try_from(row_length).map_err(|_| too_long("row"))?;
        let row_count_u32 = u32::try_from(row_count).map_err(|_| too_long("rows"))?;
        row_length_u32
            .checked_mul(row_count_u32)
            .ok_or_else(|| too_long("data"))?;

        ctx.check_subgroup_layout()?;
        let reduce = ReduceBlocks::new(ctx)?;
        let scan = ScanBlocks::new(ctx)?;
        let block = scan.0.workgroup_size()[0] * ITEMS_PER_INVOCATION;
        let mut levels = Vec::new();
        let mut length = row_length_u32.max(1);
        loop {
            let blocks_per_row = length.div_ceil(block);
            let sums = if blocks_per_row > 1 {
                let n = blocks_per_row as usize * row_count;
                let depth = levels.len();
                Some((
                    Buffer::zeroed(ctx, &format!("prefix sum block sums {depth}"), n)?,
                    Buffer::zeroed(ctx, &format!("prefix sum block offsets {depth}"), n)?,
                ))
            } else {
                None
            };
            levels.push(Level {
                row_length: length,
                blocks_per_row,
                sums,
            });
            if blocks_per_row == 1 {
                break;
            }
            length = blocks_per_row;
        }
        Ok(PrefixSum {
            reduce,
            scan,
            row_length: row_length_u32,
            row_count: row_count_u32,
            levels,
            inner_totals: Buffer::zeroed(ctx, "prefix sum inner row totals", row_count.max(1))?,
            unused_offsets: Buffer::zeroed(ctx, "prefix sum offsets (single block)", 1)?,
        })
    }

    /// Dispatches per submission (for the curious: reduce and scan per level).
    pub fn dispatch_count(&self) -> usize {
        2 * self.levels.len() - 1
    }

    /// Records `output[r][i] = sum of input[r][0..=i]` and `row_totals[r] = output[r][last]`.
    pub fn record<'a>(
        &'a self,
        cmd: &mut Commands<'a>,
        input: &'a Buffer<f32>,
        output: &'a Buffer<f32>,
        row_totals: &'a Buffer<f32>,
    ) -> GpuResult<()> {
        let n = self.row_length as usize * self.row_count as usize;
        for (buffer, expected) in [
            (input, n),
            (output, n),
            (row_totals, self.row_count as usize),
        ] {
            if buffer.len() != expected {
                return Err(GpuError::BufferLength {
                    name: buffer.name().to_string(),
                    expected,
                    given: buffer.len(),
                });
            }
        }
        if n == 0 {
            // Empty rows sum to zero.
            if self.row_count > 0 {
                cmd.fill_zero(row_totals);
            }
            return Ok(());
        }
        let params = |level: &Level| ScanParams {
            row_length: level.row_length,
            row_count: self.row_count,
            blocks_per_row: level.blocks_per_row,
            _pad: 0,
        };
        // The buffers level k reads and writes: the caller's at level 0, the block sums and
        // their scan of level k-1 above it.
        let input_of = |k: usize| {
            if k == 0 {
                input
            } else {
                &self.levels[k - 1].sums.as_ref().unwrap().0
            }
        };
        let output_of = |k: usize| {
            if k == 0 {
                output
            } else {
                &self.levels[k - 1].sums.as_ref().unwrap().1
            }
        };
        for (k, level) in self.levels.iter().enumerate() {
            if let Some((sums, _)) = &level.sums {
                self.reduce.record(cmd, input_of(k), sums, params(level))?;
            }
        }
        for (k, level) in self.levels.iter().enumerate().rev() {
            let offsets = level
                .sums
                .as_ref()
                .map_or(&self.unused_offsets, |(_, scanned)| scanned);
            let totals = if k == 0 {
                row_totals
            } else {
                &self.inner_totals
            };
            self.scan.record(
                cmd,
                input_of(k),
                offsets,
                output_of(k),
                totals,
                params(level),
            )?;
        }
        Ok(())
    }
}
