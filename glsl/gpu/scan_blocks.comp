#version 450
// Prefix sum, pass 2 of 2 (reduce-then-scan): the inclusive scan of every block, offset by the
// scanned sums of the blocks before it in its row (block_offsets, the inclusive scan of
// reduce_blocks' output; unread when a row is a single block). The invocation holding the last
// element of a row also writes the row total.
//
// Each invocation scans its SCAN_ITEMS elements in registers, the workgroup scans the
// invocation totals as a tree (workgroup_scan.glsl), and the block offset is added last: the
// longest chain of sequential additions behind an element is SCAN_ITEMS plus tree depths (see
// src/gpu/prefix_sum.rs on precision).
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
    uint first = scan_first_element(block);
    uint base = row * params.row_length + first;
    // Full blocks other than a row's last need no bounds checks and write no total.
    bool fast = scan_block_full(block) && block + 1u < params.blocks_per_row;

    float local[SCAN_ITEMS];
    float running = 0.0;
    if (fast) {
        for (uint k = 0u; k < SCAN_ITEMS; ++k) {
            running += values[base + k];
            local[k] = running;
        }
    } else {
        for (uint k = 0u; k < SCAN_ITEMS; ++k) {
            running += first + k < params.row_length ? values[base + k] : 0.0;
            local[k] = running;
        }
    }
    float block_total;
    float offset = workgroup_exclusive_add(running, block_total);
    if (block > 0u) {
        offset += block_offsets[row * params.blocks_per_row + block - 1u];
    }
    if (fast) {
        for (uint k = 0u; k < SCAN_ITEMS; ++k) {
            scanned[base + k] = offset + local[k];
        }
    } else {
        for (uint k = 0u; k < SCAN_ITEMS; ++k) {
            uint i = first + k;
            if (i < params.row_length) {
                scanned[base + k] = offset + local[k];
            }
            if (i == params.row_length - 1u) {
                row_totals[row] = offset + local[k];
            }
        }
    }
}
