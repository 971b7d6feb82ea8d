#version 450
// The leaves of the `hierarchical` sampler's pyramid (env_pyramid.glsl): each leaf's weight is
// the largest luminance among the map texels its (phi, theta) footprint touches, times the
// leaf's exact solid angle, so a sun smaller than a leaf keeps it positive. One invocation per
// leaf, (column, row) of the dispatch.

#extension GL_GOOGLE_include_directive : require

layout(local_size_x = 64, local_size_y = 1, local_size_z = 1) in;

// bvh.glsl only because the scene bindings come as one set (GpuScene::bindings).
#include "bvh.glsl"
#include "scene.glsl"
#include "sampling.glsl"
#include "env_pyramid.glsl"

void main() {
    uint i = gl_GlobalInvocationID.x;
    uint j = gl_GlobalInvocationID.y;
    uint rows = pyramid_rows();
    uint columns = 2u * rows;
    if (i >= columns || j >= rows) return;
    uint w = scene.env_size.x;
    uint h = scene.env_size.y;
    // The map texels overlapping [i, i + 1) / columns and [j, j + 1) / rows.
    uint c0 = i * w / columns;
    uint c1 = max(((i + 1u) * w + columns - 1u) / columns, c0 + 1u);
    uint r0 = j * h / rows;
    uint r1 = max(((j + 1u) * h + rows - 1u) / rows, r0 + 1u);
    float y = 0.0;
    for (uint r = r0; r < min(r1, h); ++r) {
        for (uint c = c0; c < min(c1, w); ++c) {
            y = max(y, luminance(env_texels[r * w + c].rgb));
        }
    }
    env_pyramid[j * columns + i] = y * pyramid_leaf_solid_angle(j);
}
