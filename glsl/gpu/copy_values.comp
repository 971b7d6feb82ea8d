#version 450
// Plain copy of 4 * vec4_count floats, the memory-bandwidth yardstick that `irad bench scan` sets the
// prefix sum against. vec4 accesses, consecutive invocations on consecutive vec4s, a grid-stride
// loop: the access pattern that reaches a device's copy bandwidth.

layout(local_size_x = 64, local_size_y = 1, local_size_z = 1) in;

layout(set = 0, binding = 0, std430) readonly buffer Source { vec4 source[]; };
layout(set = 0, binding = 1, std430) writeonly buffer Destination { vec4 destination[]; };

layout(push_constant) uniform CopyParams {
    uint vec4_count;
    uint _pad0;
    uint _pad1;
    uint _pad2;
} params;

void main() {
    uint stride = gl_NumWorkGroups.x * gl_WorkGroupSize.x;
    for (uint i = gl_GlobalInvocationID.x; i < params.vec4_count; i += stride) {
        destination[i] = source[i];
    }
}
