#version 450
// Prefix sum, pass 1 of 2 (reduce-then-scan): the sum of every block of every row,
// block_sums[row * blocks_per_row + block]. Each invocation sums its SCAN_ITEMS elements (scan_layout.glsl), then the workgroup sums those as a tree (workgroup_scan.glsl).
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
    uint first = scan_first_element(block);
    uint row_base = row * params.row_length;
    float sum = 0.0;
    if (scan_block_full(block)) {
        for (uint j = 0u; j < SCAN_ITEMS; ++j) {
            sum += values[row_base + first + j];
        }
    } else {
        for (uint j = 0u; j < SCAN_ITEMS; ++j) {
            uint i = first + j;
            sum += i < params.row_length ? values[row_base + i] : 0.0;
        }
    }
    float total;
    workgroup_exclusive_add(sum, total);
    if (gl_LocalInvocationIndex == 0u) {
        block_sums[row * params.blocks_per_row + block] = total;
    }
}
