#version 450
// Prefix sum, pass 2 of 2 (reduce-then-scan): the inclusive scan of every block, offset by the
// scanned sums of the blocks before it in its row (block_offsets, the inclusive scan of
// reduce_blocks' output; unread when a row is a single block). The workgroup owning the last
// block of a row also writes the row total.
#extension GL_KHR_shader_subgroup_arithmetic : require
#extension GL_GOOGLE_include_directive : require

#include "scan_layout.glsl"
#include "workgroup_scan.glsl"

layout(set = 0, binding = 0, std430) readonly buffer Values { float values[]; };
layout(set = 0, binding = 1, std430) readonly buffer BlockOffsets { float block_offsets[]; };
layout(set = 0, binding = 2, std430) writeonly buffer Scanned { float scanned[]; };
layout(set = 0, binding = 3, std430) writeonly buffer RowTotals { float row_totals[]; };

void main() {
    uint row, block;
    if (!scan_block(row, block)) {
        return; // uniform over the workgroup
    }
    uint first = block * SCAN_BLOCK + gl_LocalInvocationID.x * SCAN_ITEMS;
    uint row_base = row * params.row_length;

    float local[SCAN_ITEMS];
    float running = 0.0;
    for (uint k = 0u; k < SCAN_ITEMS; ++k) {
        uint i = first + k;
        running += i < params.row_length ? values[row_base + i] : 0.0;
        local[k] = running;
    }
    float block_total;
    float offset = workgroup_exclusive_add(running, block_total);
    if (block > 0u) {
        offset += block_offsets[row * params.blocks_per_row + block - 1u];
    }
    for (uint k = 0u; k < SCAN_ITEMS; ++k) {
        uint i = first + k;
        if (i < params.row_length) {
            scanned[row_base + i] = offset + local[k];
        }
        if (i == params.row_length - 1u) {
            row_totals[row] = offset + local[k];
        }
    }
}
