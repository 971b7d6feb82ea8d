// Block layout shared by the prefix-sum kernels (reduce_blocks.comp, scan_blocks.comp).
//
// Data is `row_count` rows of `row_length` floats, row-major. Each row is cut into blocks of
// SCAN_BLOCK = 64 invocations x SCAN_ITEMS elements; a workgroup owns one block, and each
// invocation SCAN_ITEMS consecutive elements of it, summed in sequence in registers. (Measured on
// lavapipe: raking each subgroup over chunks of gl_SubgroupSize consecutive elements, one
// subgroup scan per chunk, ran 1.3-1.6x slower, as lavapipe runs subgroup scans lane by lane;
// staging blocks through shared memory for contiguous global access ran 1.5x slower, barriers
// being lavapipe's costliest operation; 32 items per invocation did not help.)
// Workgroups are numbered over a 2D grid (x fastest) so that long rows and many rows both stay
// under maxComputeWorkGroupCount.

#ifndef SCAN_LAYOUT_GLSL
#define SCAN_LAYOUT_GLSL

#define SCAN_THREADS 64u
#define SCAN_ITEMS 16u
#define SCAN_BLOCK (SCAN_THREADS * SCAN_ITEMS)

layout(local_size_x = 64, local_size_y = 1, local_size_z = 1) in;

layout(push_constant) uniform ScanParams {
    uint row_length;     // elements per row
    uint row_count;      // rows
    uint blocks_per_row; // ceil(row_length / SCAN_BLOCK)
    uint _pad;
} params;

// The block this workgroup owns, or false when the grid's last row of workgroups overhangs.
bool scan_block(out uint row, out uint block) {
    uint linear = gl_WorkGroupID.x + gl_WorkGroupID.y * gl_NumWorkGroups.x;
    row = linear / params.blocks_per_row;
    block = linear - row * params.blocks_per_row;
    return row < params.row_count;
}

// Index within its row of this invocation's first element; its k-th is that plus k.
uint scan_first_element(uint block) {
    return block * SCAN_BLOCK + gl_LocalInvocationIndex * SCAN_ITEMS;
}

// Whether the whole block lies inside its row (no bounds checks needed).
bool scan_block_full(uint block) {
    return (block + 1u) * SCAN_BLOCK <= params.row_length;
}

#endif
