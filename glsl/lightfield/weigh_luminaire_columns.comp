#version 450
// The light-field luminaire's sampling tables, step 1 (src/methods/lightfield/tables.rs): the
// luminance of every texel of every image (Lu 14 Section 4.4: sampling by luminance, colour as
// a ratio), written column by column, so that the prefix sum over each column's run gives the
// conditional CDFs in t (Eq. 4.10). Input texels: image m, row t, column s (RGB); output:
// image m, column s, row t. One invocation per texel: (s, t, m) of the dispatch.

layout(local_size_x = 8, local_size_y = 8, local_size_z = 1) in;

layout(set = 0, binding = 0, std430) readonly buffer LuminaireTexels { vec4 texels[]; };
layout(set = 0, binding = 1, std430) writeonly buffer ColumnValues { float columns[]; };

layout(push_constant) uniform WeighParams {
    uint width;   // R_s
    uint height;  // R_t
    uint images;  // M
} params;

void main() {
    uint s = gl_GlobalInvocationID.x;
    uint t = gl_GlobalInvocationID.y;
    uint m = gl_GlobalInvocationID.z;
    if (s >= params.width || t >= params.height || m >= params.images) return;
    vec3 c = texels[(m * params.height + t) * params.width + s].rgb;
    float y = max(dot(c, vec3(0.2126, 0.7152, 0.0722)), 0.0);
    columns[(m * params.width + s) * params.height + t] = y;
}
