#version 450
// ReSTIR DI's shading: each pixel's final reservoir's sample, f Le cos G W, added into the
// accumulation (Bitterli et al. 2020, Eq. 6 with one sample). Its visibility is already in W
// (restir.glsl's invariant), so no shadow ray here. The emission the camera sees is the
// driver's direct-light pass (depth 0).

#extension GL_GOOGLE_include_directive : require

layout(local_size_x = 8, local_size_y = 8, local_size_z = 1) in;

#include "scene.glsl"
#include "sampling.glsl"
#include "bsdf.glsl"
#include "envmap.glsl"
#include "lights.glsl"
#include "gbuffer.glsl"
#include "radiance.glsl"

// restir.glsl without the BVH: this kernel traces nothing.
#define RESTIR_NO_TRACE
#include "restir.glsl"

void main() {
    uvec2 pixel = gl_GlobalInvocationID.xy;
    if (pixel.x >= scene.size.x || pixel.y >= scene.size.y) return;
    uint index = pixel.y * scene.size.x + pixel.x;
    RestirPoint s = restir_point_from_gbuffer(index);
    Reservoir r = final_reservoirs[index];
    if (!s.valid) return;
    // A NaN W (reuse's weights out of f32's range) is dropped and counted; Inf is counted below.
    if (isnan(r.weights.x)) {
        count_nonfinite_estimate();
        return;
    }
    if (!(r.weights.x > 0.0)) return;
    // The integrand with the textured albedo; every target function (restir.glsl) takes the
    // material's untextured Kd, which is positive wherever the textured one is, so the
    // estimator stays unbiased, and a surface stored by the previous frame needs no texture
    // coordinates.
    s.m = gbuffer_material(gbuffer[index]);
    vec3 wi;
    float dist, to_area;
    vec3 c = restir_contribution(s, floatBitsToUint(r.sample_point.w), r.sample_point.xyz, wi,
                                 dist, to_area);
    accumulate_radiance(index, c * r.weights.x);
}
