#version 450
// The light-field luminaire's sampling tables, step 3 (src/methods/lightfield/tables.rs): the
// column CDFs (image m, column s, row t: the integral over [0, t + 1] of column s) laid out row
// by row (image m, row t, column s), so that a prefix sum along each row turns them into the
// summed-area table, SAT(s, t) = the integral over [0, s + 1] x [0, t + 1] (Section 4.5: A_m(p)
// from four lookups). One invocation per texel: (s, t, m) of the dispatch.

layout(local_size_x = 8, local_size_y = 8, local_size_z = 1) in;

layout(set = 0, binding = 0, std430) readonly buffer ColumnCdf { float column_cdf[]; };
layout(set = 0, binding = 1, std430) writeonly buffer RowValues { float rows[]; };

layout(push_constant) uniform TransposeParams {
    uint width;   // R_s
    uint height;  // R_t
    uint images;  // M
} params;

void main() {
    uint s = gl_GlobalInvocationID.x;
    uint t = gl_GlobalInvocationID.y;
    uint m = gl_GlobalInvocationID.z;
    if (s >= params.width || t >= params.height || m >= params.images) return;
    rows[(m * params.height + t) * params.width + s] =
        column_cdf[(m * params.width + s) * params.height + t];
}
