// Workgroup-wide exclusive sum of one float per invocation, for 1D workgroups.
//
// Subgroup arithmetic first (8 lanes on lavapipe, 32 on NVIDIA, 64 on AMD wave64), then each
// invocation adds the totals of the subgroups before its own, read from shared memory: one
// barrier in all (docs/DESIGN.md "gallivm runs every lane under masks": barriers are what costs on lavapipe). The sums form a tree, so the
// rounding error grows with log2(workgroup size), not with the workgroup size.
//
// Requires: GL_KHR_shader_subgroup_arithmetic, a 1D workgroup of at most WORKGROUP_SUM_SLOTS
// subgroups, and at most one call per workgroup invocation (the shared slots are not reset).
// The sums run in (gl_SubgroupID, lane) order; callers index data by gl_LocalInvocationIndex,
// which every driver we know maps onto that order (the spec does not promise it), so
// src/gpu/subgroup_layout.rs checks it once per device before the first scan.

#ifndef WORKGROUP_SCAN_GLSL
#define WORKGROUP_SCAN_GLSL

#ifndef WORKGROUP_SUM_SLOTS
#define WORKGROUP_SUM_SLOTS 64
#endif

shared float workgroup_subgroup_totals[WORKGROUP_SUM_SLOTS];

// Returns the sum of `value` over the invocations before this one (exclusive) and writes the sum
// over the whole workgroup to `total`. Exclusive sums are formed directly, never as an inclusive
// sum minus the own value: that subtraction cancels catastrophically after a large value.
float workgroup_exclusive_add(float value, out float total) {
    float within = subgroupExclusiveAdd(value);
    // Written by one active lane, not by lane gl_SubgroupSize - 1: subgroups may be partly
    // filled (Intel and MoltenVK may run narrower than gl_SubgroupSize; a 128-wide Adreno
    // subgroup is half empty in a 64-invocation workgroup).
    float subgroup_total = subgroupAdd(value);
        // The lowest active lane (subgroupElect's choice; naga's reflection rejects OpGroupNonUniformElect).
    if (gl_SubgroupInvocationID == subgroupMin(gl_SubgroupInvocationID)) {
        workgroup_subgroup_totals[gl_SubgroupID] = subgroup_total;
    }
    barrier();
    float before = 0.0;
    total = 0.0;
    for (uint s = 0u; s < gl_NumSubgroups; ++s) {
        float t = workgroup_subgroup_totals[s];
        if (s < gl_SubgroupID) {
            before += t;
        }
        total += t;
    }
    return before + within;
}

#endif
