#version 450
// The weights of the equirectangular sampling table (equirect_table.glsl): each texel's
// (Y(Le) + offset) times its solid angle. The offset is Tokuyoshi 12 Eq. 2's Lo for the bundle
// directions and 0 for light sampling. The GPU prefix sums turn the weights into the table.
// One invocation per texel, (column, row) of the dispatch.

#extension GL_GOOGLE_include_directive : require

layout(local_size_x = 64, local_size_y = 1, local_size_z = 1) in;

// bvh.glsl only because the scene bindings come as one set (GpuScene::bindings).
#include "bvh.glsl"
#include "scene.glsl"
#include "sampling.glsl"
#include "envmap.glsl"

layout(set = 0, binding = 15, std430) writeonly buffer EquirectWeights { float weights[]; };

layout(push_constant) uniform WeighParams {
    float offset;  // added to every texel's luminance
} params;

void main() {
    uint i = gl_GlobalInvocationID.x;
    uint j = gl_GlobalInvocationID.y;
    uint w = scene.env_size.x;
    uint h = scene.env_size.y;
    if (i >= w || j >= h) return;
    float y = max(luminance(env_texels[j * w + i].rgb), 0.0);
    weights[j * w + i] = (y + max(params.offset, 0.0)) * env_texel_solid_angle(j);
}
