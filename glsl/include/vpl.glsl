// Virtual point lights (Keller 97): written by trace_vpls.comp, shaded by
// accumulate_vpls_tiled.comp. Binding 13.
#ifndef VPL_GLSL
#define VPL_GLSL

#define VPL_NONE 0u     // an empty slot (the walk ended before this vertex)
#define VPL_SURFACE 1u  // a path vertex on a surface: reflects by the BSDF at it
#define VPL_AREA 2u     // a start point on an emissive triangle: cosine emitter
#define VPL_POINT 3u    // a point light's position: isotropic
#define VPL_SPOT 4u     // a spot light's position: pbrt smoothstep falloff

struct Vpl {
    vec4 position;  // w: kind (uint bits)
    vec4 normal;    // surface: unit, on the side the light arrived from; area: emitting side;
                    // spot: the axis. w: material (surface, uint bits), cos(falloff) (spot)
    vec4 power;     // rgb: this VPL's share of the flux (its estimator weight included);
                    // w: cos(cone) (spot); the triangle (surface, uint bits)
    vec4 incident;  // surface: unit direction toward where the light came from
};

// A kernel that defines VPL_NO_BUFFER gets the layout only (every declared buffer must be
// bound).
#ifndef VPL_NO_BUFFER
#if defined(VPL_READ_WRITE)
layout(set = 0, binding = 13, std430) buffer Vpls { Vpl vpls[]; };
#elif defined(VPL_WRITE)
layout(set = 0, binding = 13, std430) writeonly buffer Vpls { Vpl vpls[]; };
#else
layout(set = 0, binding = 13, std430) readonly buffer Vpls { Vpl vpls[]; };
#endif
#endif

uint vpl_kind(Vpl v) {
    return floatBitsToUint(v.position.w);
}

#endif
