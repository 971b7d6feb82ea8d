// Bias compensation of the clamped VPL gather (Kollig and Keller 2004, "Illumination in the
// presence of weak singularities", Section 3): the gather clamps the geometry term at b; what
// the clamp removes, the integral over directions w at x of f cos (1 - b / G(x, y))+ L_r(y),
// y the closest hit along w, is added back by short camera-side paths (BSDF-sampled from x)
// that continue only while G(x, y) > b. At each path vertex y, L_r(y) is next-event
// estimation plus the same clamped gather plus, recursively, its compensation; the last
// level's gather is unclamped, so the estimator is unbiased at any depth
// (src/methods/compensation.rs). Written by trace_compensation_paths.comp, gathered by
// gather_compensation_vpls.comp. Bindings 14 (in), 15 (out), 16 (counts).
#ifndef COMPENSATION_GLSL
#define COMPENSATION_GLSL

struct CompensationVertex {
    vec4 position;  // y; w: the pixel it adds into (uint bits)
    vec4 normal;    // shading normal at y on the side of wo; w: material (uint bits)
    vec4 side;      // geometric normal at y on the side of wo; w: its GPU triangle (uint bits)
    vec4 wo;        // unit, toward the previous vertex
    vec4 beta;      // rgb: throughput from the pixel, the (1 - b / G) factors included
};

// counts[l]: vertices of level l (1-based) this frame.
layout(set = 0, binding = 16, std430) buffer CompensationCounts { uint counts[]; };

#endif
