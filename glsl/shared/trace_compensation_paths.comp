#version 450
// One level of the clamp's compensation paths (include/compensation.glsl; Kollig and Keller
// 2004): from each vertex of level l - 1 (the G-buffer's first hits for l = 1), a BSDF-sampled
// direction w to the closest hit y. Where the VPL gather's geometry term G(x, y) (cos at x
// from the shading normal, cos at y from y's shading normal on x's side, over d^2, exactly as
// vpl_shading.glsl computes it for a VPL at y) exceeds the clamp b, y becomes a level-l vertex
// with throughput beta f cos / pdf (1 - b / G), its direct light is added by next-event
// estimation (one light by power, weight 1: the path never counts emission it hits, which the
// direct-light pass owns), and gather_compensation_vpls.comp adds its VPL light.
//
// Random dimensions per (seed, pixel, frame), 8 per level from 8 l: BSDF lobe and direction
// (+0..+2), light selection (+3), light point (+4, +5), environment texel (+6).

#extension GL_GOOGLE_include_directive : require

layout(local_size_x = 64, local_size_y = 1, local_size_z = 1) in;

#include "bvh.glsl"
#include "scene.glsl"
#include "sampling.glsl"
#include "bsdf.glsl"
#include "lights.glsl"
#include "gbuffer.glsl"
#include "radiance.glsl"
#include "compensation.glsl"

layout(push_constant) uniform CompensationParams {
    uint level;   // l >= 1: reads level l - 1, writes level l
    uint frame;
    uint seed;
    float g_clamp;  // b > 0
    float direct_weight;  // multiplies the next-event term: the share of the frame's estimate
                          // the compensated gather is (bir without resampling: 1 / batches)
} params;

layout(set = 0, binding = 14, std430) readonly buffer CompensationIn { CompensationVertex vertices_in[]; };
layout(set = 0, binding = 15, std430) writeonly buffer CompensationOut { CompensationVertex vertices_out[]; };

float max_component(vec3 v) {
    return max(max(v.x, v.y), v.z);
}

void main() {
    uint i = gl_GlobalInvocationID.x;
    vec3 x, n, side, wo, beta;
    uint pixel, mat, tri;
    if (params.level <= 1u) {
        if (i >= scene.size.x * scene.size.y) return;
        GBufferTexel g = gbuffer[i];
        if (!gbuffer_surface(g, wo, side, n)) return;
        x = g.position.xyz;
        mat = floatBitsToUint(g.shading_normal.w);
        tri = floatBitsToUint(g.geometric_normal.w);
        beta = vec3(1.0);
        pixel = i;
    } else {
        if (i >= counts[params.level - 1u]) return;
        CompensationVertex v = vertices_in[i];
        x = v.position.xyz;
        pixel = floatBitsToUint(v.position.w);
        n = v.normal.xyz;
        mat = floatBitsToUint(v.normal.w);
        tri = floatBitsToUint(v.side.w);
        side = v.side.xyz;
        wo = v.wo.xyz;
        beta = v.beta.rgb;
    }
    Material m = textured(materials[mat], mat, tri, x);
    uint dim = 8u * params.level;
    vec3 u = vec3(random(params.seed, pixel, params.frame, dim),
                  random(params.seed, pixel, params.frame, dim + 1u),
                  random(params.seed, pixel, params.frame, dim + 2u));
    vec3 wi;
    if (!bsdf_sample(m, n, wo, u, wi)) return;
    float pdf = bsdf_pdf(m, n, wo, wi);
    float cos_i = dot(wi, n);
    if (pdf <= 0.0 || cos_i <= 0.0 || dot(wi, side) <= 0.0) return;
    vec3 origin = offset_origin(x, side);
    // G > b needs |y - x|^2 < 1 / b (both cosines at most 1): the ray need not go further than
    // 1 / sqrt(b) plus the origin's offset, and a short ray visits few BVH nodes. Same hits
    // (a closest hit beyond the reach has G <= b and adds nothing), so the same bits.
    float reach = inversesqrt(params.g_clamp) + 2.0 * distance(origin, x);
    RayHit hit;
    if (!trace_closest(origin, wi, reach, hit)) return;
    vec3 y = origin + hit.t * wi;

    // The gather's G for a VPL at y: its direction from x (not from the offset origin).
    vec3 d = y - x;
    float dist2 = dot(d, d);
    if (!(dist2 > 0.0)) return;
    vec3 w = d * inversesqrt(dist2);
    vec3 ng_y = shading_triangles[hit.triangle].geometric_normal.xyz;
    vec3 ns_y = shading_normal(hit.triangle, hit.barycentrics);
    vec3 wo_y = -wi;
    vec3 side_y = dot(wo_y, ng_y) >= 0.0 ? ng_y : -ng_y;
    vec3 n_y = dot(ns_y, side_y) >= 0.0 ? ns_y : -ns_y;
    float g = max(dot(n, w), 0.0) * max(dot(n_y, -w), 0.0) / dist2;
    if (!(g > params.g_clamp)) return;
    beta *= bsdf_eval(m, n, wo, wi) * (cos_i / pdf) * (1.0 - params.g_clamp / g);
    if (!(max_component(beta) > 0.0)) return;

    // Direct light at y by next-event estimation.
    uint mat_y = triangle_material(hit.triangle);
    Material my = textured(materials[mat_y], mat_y, hit.triangle, y);
    vec3 origin_y = offset_origin(y, side_y);
    LightSample ls;
    uint r_select = random_u31(params.seed, pixel, params.frame, dim + 3u);
    uint r_texel = random_u31(params.seed, pixel, params.frame, dim + 6u);
    vec2 u_light = vec2(random(params.seed, pixel, params.frame, dim + 4u),
                        random(params.seed, pixel, params.frame, dim + 5u));
    if (sample_light(y, r_select, r_texel, u_light, ls)) {
        float cos_l = dot(ls.direction, n_y);
        if (cos_l > 0.0 && dot(ls.direction, side_y) > 0.0) {
            vec3 f = bsdf_eval(my, n_y, wo_y, ls.direction);
            if (max_component(f) > 0.0) {
                bool visible;
                if (isinf(ls.distance)) {
                    visible = !trace_any(origin_y, ls.direction, infinity());
                } else {
                    vec3 to_light = y + ls.direction * ls.distance - origin_y;
                    visible = !trace_any(origin_y, to_light, 0.9999);
                }
                if (visible) {
                    accumulate_radiance(
                        pixel, beta * f * cos_l * ls.radiance * (params.direct_weight / ls.pdf));
                }
            }
        }
    }

    uint slot = atomicAdd(counts[params.level], 1u);
    CompensationVertex v;
    v.position = vec4(y, uintBitsToFloat(pixel));
    v.normal = vec4(n_y, uintBitsToFloat(mat_y));
    v.side = vec4(side_y, uintBitsToFloat(hit.triangle));
    v.wo = vec4(wo_y, 0.0);
    v.beta = vec4(beta, 0.0);
    vertices_out[slot] = v;
}
