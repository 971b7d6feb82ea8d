// Block layout shared by the prefix-sum kernels (reduce_blocks.comp, scan_blocks.comp).
//
// Data is `row_count` rows of `row_length` floats, row-major. Each row is cut into blocks of
// SCAN_BLOCK = 64 invocations x SCAN_ITEMS consecutive elements; a workgroup owns one block.
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

#endif
