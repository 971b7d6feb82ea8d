#version 450
// Prefix sum, pass 1 of 2 (reduce-then-scan): the sum of every block of every row.
// block_sums[row * blocks_per_row + block]. Each invocation sums SCAN_ITEMS consecutive
// elements, then the workgroup sums those as a tree (workgroup_scan.glsl).
#extension GL_KHR_shader_subgroup_arithmetic : require
#extension GL_GOOGLE_include_directive : require

#include "scan_layout.glsl"
#include "workgroup_scan.glsl"

layout(set = 0, binding = 0, std430) readonly buffer Values { float values[]; };
layout(set = 0, binding = 1, std430) writeonly buffer BlockSums { float block_sums[]; };

void main() {
    uint row, block;
    if (!scan_block(row, block)) {
        return; // uniform over the workgroup
    }
    uint first = block * SCAN_BLOCK + gl_LocalInvocationID.x * SCAN_ITEMS;
    uint row_base = row * params.row_length;
    float sum = 0.0;
    for (uint k = 0u; k < SCAN_ITEMS; ++k) {
        uint i = first + k;
        if (i < params.row_length) {
            sum += values[row_base + i];
        }
    }
    float total;
    workgroup_exclusive_add(sum, total);
    if (gl_LocalInvocationID.x == 0u) {
        block_sums[row * params.blocks_per_row + block] = total;
    }
}
