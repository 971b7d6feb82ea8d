#version 450
// One level of the `hierarchical` sampler's pyramid (env_pyramid.glsl): texel (i, j) of
// level l + 1 is the sum of the 2x2 block (2i..2i+1, 2j..2j+1) of level l. One invocation per
// texel of level l + 1; dispatched once per level, finest first.

#extension GL_GOOGLE_include_directive : require

layout(local_size_x = 64, local_size_y = 1, local_size_z = 1) in;

#include "bvh.glsl"
#include "scene.glsl"
#include "sampling.glsl"
#include "env_pyramid.glsl"

layout(push_constant) uniform ReduceParams {
    uint level;  // l: the level read
} params;

void main() {
    uint i = gl_GlobalInvocationID.x;
    uint j = gl_GlobalInvocationID.y;
    uint rows = pyramid_rows() >> (params.level + 1u);
    uint columns = 2u * rows;
    if (i >= columns || j >= rows) return;
    uint below = pyramid_offset(params.level);
    uint width = 2u * columns;
    float sum = (pyramid_weight(below, width, 2u * i, 2u * j) +
                 pyramid_weight(below, width, 2u * i + 1u, 2u * j)) +
                (pyramid_weight(below, width, 2u * i, 2u * j + 1u) +
                 pyramid_weight(below, width, 2u * i + 1u, 2u * j + 1u));
    env_pyramid[pyramid_offset(params.level + 1u) + j * columns + i] = sum;
}
