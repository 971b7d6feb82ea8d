#version 450
// Records how the device numbers a 64-invocation workgroup's subgroup lanes: per invocation,
// (gl_LocalInvocationIndex, gl_SubgroupID, gl_SubgroupInvocationID, gl_SubgroupSize).
// workgroup_scan.glsl sums in (gl_SubgroupID, lane) order while its callers index data by
// gl_LocalInvocationIndex; the spec does not promise the two orders agree, so
// src/gpu/subgroup_layout.rs checks them once per device before any scan runs.
#extension GL_KHR_shader_subgroup_basic : require

layout(local_size_x = 64, local_size_y = 1, local_size_z = 1) in;

layout(set = 0, binding = 0, std430) writeonly buffer Layout { uvec4 layout_records[]; };

void main() {
    layout_records[gl_LocalInvocationIndex] = uvec4(gl_LocalInvocationIndex, gl_SubgroupID,
                                                    gl_SubgroupInvocationID, gl_SubgroupSize);
}
