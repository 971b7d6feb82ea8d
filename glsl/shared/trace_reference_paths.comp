#version 450
// The reference: one unidirectional path per pixel per frame from the G-buffer's first hit
// (pbrt-v4 PathIntegrator, Pharr et al. 2023 Section 13.4): emission, next-event estimation
// of one light chosen by power (lights.glsl) or through the light BVH (light_bvh.glsl, the
// constant LIGHT_BVH), BSDF sampling (bsdf.glsl), the two combined by
// the power heuristic (Veach 1997 Section 9.2), Russian roulette from bounce 3 on. Delta
// lights are reached by next-event estimation only, with weight 1.
//
// Speed on lavapipe (docs/DESIGN.md "gallivm runs every lane under masks"). gallivm runs every instruction of a kernel under
// lane masks: both sides of every branch whether any lane takes it, every loop body to its end
// before it tests for live lanes, every storage-buffer load as a loop over the lanes. So the
// time is the code run per loop iteration, and it is won by running less code, not by keeping
// lanes busy. Cornell box 256x256, 32 spp, medians of interleaved runs, in steps (total GPU
// time, G-buffer pass included): 2.63 s before; specialized to the scene's features
// (scene.glsl) 2.29 s; each new hit handled at the end of the iteration that found it (the
// loop exits there instead of after one more masked body) 2.04 s; scene constants in a uniform
// block 1.93 s; each hit's triangle and material loaded once 1.92 s (1.83 s in another run);
// one shadow-ray traversal instead of two (environment and finite) 1.80 s. In a later run,
// 2.59 s before, 1.70 s with those; bvh.glsl's triangle loop a do-while 1.67 s (closest-hit
// rays 10-20% faster on `irad bench rays`); the start (G-buffer or camera) a specialization
// constant, so the path loop is in the kernel once, not twice, 1.46 s: 1.77x in all, the same
// bits (camera starts, ir's and bir's direct light: the same pixels, 2x faster). Tried and
// not kept: the reference's camera ray traced here instead of read from the G-buffer (1.56 s
// against 1.46 s); the BVH in uniform blocks (gathered loads; 0.6-1.0x on `irad bench rays`);
// the hash of (seed, pixel, sample) computed once per path (no change: LLVM hoists it).
//
// Path regeneration was measured and not kept: S paths per invocation from camera rays traced
// in this kernel, an ended path replaced at once by the pixel's next sample, every loop
// iteration tracing one closest-hit ray (a bounce's or a new camera ray) on one code path.
// Cornell box 256x256, 32 spp, lavapipe, medians of 3 interleaved runs: G-buffer pass + this
// kernel 6.14 s; regeneration S = 1 6.33 s, S = 4 5.86 s, S = 8 5.72 s (1.07x at best; same
// image to f32 rounding).
//
// Random dimensions per (seed, pixel, frame), 8 per bounce from 2: light selection (+0), light
// position (+1, +2), environment texel (+7), BSDF lobe and direction (+3..+5), roulette (+6).
// (The subpixel shift is dimensions 0-1 at sample index 0xffffffff: camera.glsl.)

#extension GL_GOOGLE_include_directive : require

layout(local_size_x = 8, local_size_y = 8, local_size_z = 1) in;

#include "bvh.glsl"
#include "scene.glsl"
#include "sampling.glsl"
#include "bsdf.glsl"
#include "lights.glsl"
#include "light_bvh.glsl"
#include "gbuffer.glsl"
#include "camera.glsl"
#include "radiance.glsl"

layout(push_constant) uniform PathParams {
    uint frame;
    uint seed;
    uint max_depth;       // most scattering events per path (pbrt's maxdepth)
    uint roulette_depth;  // first bounce at which Russian roulette may end the path
    uint environment;     // 0: the environment is seen by the camera only, not reflected (a
                          // method that estimates its reflection itself: bundles)
    uint camera_samples;  // 0: one path from the G-buffer's hit, sample index `frame`; K > 0:
                          // K paths per pixel, each from its own camera ray at subpixel
                          // position and sample index frame * K + k, weighted 1 / K (the
                          // many-light methods' --direct-spp: direct light and the pixel
                          // footprint get K samples per frame)
    uint first_sample;    // with camera_samples: this dispatch's samples are k = first_sample
    uint sample_count;    // .. first_sample + sample_count - 1 (split so no invocation runs
                          // past lavapipe's loop budget: src/methods/paths.rs)
    uint centred;         // with camera_samples: 1 aims every camera ray at the pixel centre
} params;

// Where paths start (src/methods/paths.rs specializes it): false, the G-buffer's hit; true,
// params.camera_samples camera rays traced here. A constant, not a push constant: gallivm
// would run the other mode's copy of the path loop too, masked (scene.glsl says why).
layout(constant_id = 4) const bool CAMERA_STARTS = false;
// How next-event estimation chooses its light (src/methods/paths.rs specializes it): false, by
// power (the light table); true, through the light BVH. A constant for the same reason.
layout(constant_id = 5) const bool LIGHT_BVH = false;

const uint DIMENSIONS_PER_BOUNCE = 8u;

float max_component(vec3 v) {
    return max(max(v.x, v.y), v.z);
}

// The path's estimate from its first hit (found false: the camera ray `dir` missed).
vec3 path_radiance(uint index, uint sample_index, vec3 dir, bool found, vec3 p, float t,
                   uint tri, vec3 ns, vec3 ng, uint mat) {
    // Lights next-event estimation draws from: all, or, with the environment left out, the
    // entries before its own (the last), whose share of the table is `mass`.
    uint entries = scene.size.z;
    uint bound = 0x80000000u;
    if (params.environment == 0u && scene.env.x > 0.0) {
        entries -= 1u;
        bound = entries == 0u ? 0u : light_entries[entries - 1u].upper;
    }
    float mass = float(bound) / 2147483648.0;

    vec3 L = vec3(0.0);
    vec3 beta = vec3(1.0);
    float bsdf_pdf_prev = 0.0;

    // The first hit, then the loop, which looks at each new hit at the end of the iteration
    // that found it: gallivm (lavapipe) runs a loop body to its end under masks and tests for
    // live lanes there, so an exit decided at the top of an iteration costs a whole body.
    if (!found) {
        vec3 le = SCENE_HAS_ENVIRONMENT ? env_radiance(dir) : vec3(0.0);
        return le;
    }
    // The material at the path's vertex, loaded once per hit.
    Material m = textured(materials[mat], mat, tri, p);
    if (m.ke.w > 0.0 && dot(-dir, ng) > 0.0) L += m.ke.rgb;
    if (params.max_depth == 0u) return L;

    for (uint depth = 0u;; ++depth) {
        vec3 wo = -dir;

        // Two-sided scattering: work on the side the path arrives from.
        vec3 side = dot(wo, ng) >= 0.0 ? ng : -ng;
        vec3 n = dot(ns, side) >= 0.0 ? ns : -ns;
        vec3 origin = offset_origin(p, side);
        uint dim = 2u + depth * DIMENSIONS_PER_BOUNCE;

        LightSample ls;
        uint r_select = random_u31(params.seed, index, sample_index, dim);
        uint r_texel = random_u31(params.seed, index, sample_index, dim + 7u);
        vec2 u_light = vec2(random(params.seed, index, sample_index, dim + 1u),
                            random(params.seed, index, sample_index, dim + 2u));
        if (bound < 0x80000000u) {
            // Rescaled below the bound (select_light_among keeps it among the first entries).
            r_select = bound == 0u ? 0u : min(uint(float(r_select) * mass), bound - 1u);
        }
        bool sampled = LIGHT_BVH
            ? sample_light_bvh(p, n, r_select, mass, r_texel, u_light, ls)
            : sample_light_among(p, r_select, entries, mass, r_texel, u_light, ls);
        if (sampled) {
            float cos_i = dot(ls.direction, n);
            if (cos_i > 0.0 && dot(ls.direction, side) > 0.0) {
                vec3 f = bsdf_eval(m, n, wo, ls.direction);
                if (max_component(f) > 0.0) {
                    // Toward the environment, or at the light point itself, stopping just
                    // short of it; one call, as gallivm runs both sides of a branch.
                    bool distant = isinf(ls.distance);
                    vec3 to_light = distant ? ls.direction
                                            : p + ls.direction * ls.distance - origin;
                    if (!trace_any(origin, to_light, distant ? infinity() : 0.9999)) {
                        float w = ls.delta ? 1.0 : power_heuristic(ls.pdf, bsdf_pdf(m, n, wo, ls.direction));
                        L += beta * f * cos_i * ls.radiance * (w / ls.pdf);
                    }
                }
            }
        }

        vec3 u_bsdf = vec3(random(params.seed, index, sample_index, dim + 3u),
                           random(params.seed, index, sample_index, dim + 4u),
                           random(params.seed, index, sample_index, dim + 5u));
        vec3 wi;
        if (!bsdf_sample(m, n, wo, u_bsdf, wi)) break;
        float pdf = bsdf_pdf(m, n, wo, wi);
        float cos_i = dot(wi, n);
        if (pdf <= 0.0 || cos_i <= 0.0 || dot(wi, side) <= 0.0) break;
        beta *= bsdf_eval(m, n, wo, wi) * (cos_i / pdf);
        if (max_component(beta) <= 0.0) break;
        bsdf_pdf_prev = pdf;

        if (depth + 1u >= params.roulette_depth) {
            float q = max(0.0, 1.0 - max_component(beta));
            if (random(params.seed, index, sample_index, dim + 6u) < q) break;
            beta /= 1.0 - q;
        }

        RayHit hit;
        dir = wi;
        // The vertex the light BVH chose its light for, which its pmf on a hit needs.
        vec3 p_light = p;
        vec3 n_light = n;
        found = trace_closest(origin, wi, infinity(), hit);
        if (!found) {
            if (params.environment != 0u && SCENE_HAS_ENVIRONMENT) {
                vec3 le = env_radiance(dir);
                if (max_component(le) > 0.0) {
                    L += beta * le * power_heuristic(bsdf_pdf_prev, light_pdf_environment(dir));
                }
            }
            break;
        }
        t = hit.t;
        p = origin + t * wi;
        ShadingTriangle st = shading_triangles[hit.triangle];
        ns = interpolated_normal(st, hit.barycentrics);
        ng = st.geometric_normal.xyz;
        m = textured(materials[floatBitsToUint(st.n0.w)], floatBitsToUint(st.n0.w), hit.triangle, p);
        if (m.ke.w > 0.0 && dot(-dir, ng) > 0.0) {
            float light_pdf = 0.0;
            if (mass > 0.0) {
                light_pdf = LIGHT_BVH
                    ? light_pdf_triangle_chosen(st, dir, t,
                                                light_bvh_triangle_probability(st, p_light, n_light))
                    : light_pdf_shading_triangle(st, dir, t);
                light_pdf /= mass;
            }
            L += beta * m.ke.rgb * power_heuristic(bsdf_pdf_prev, light_pdf);
        }
        if (depth + 1u >= params.max_depth) break;
    }
    return L;
}

void main() {
    uvec2 pixel = gl_GlobalInvocationID.xy;
    if (pixel.x >= scene.size.x || pixel.y >= scene.size.y) return;
    uint index = pixel.y * scene.size.x + pixel.x;

    if (CAMERA_STARTS) {
        vec3 sum = vec3(0.0);
        vec3 origin = scene.camera_position.xyz;
        // A do-while (bvh.glsl's triangle loop says why); sample_count is at least 1.
        uint k = params.first_sample;
        do {
            uint sample_index = params.frame * params.camera_samples + k;
            vec2 subpixel = params.centred != 0u
                ? vec2(0.5) : subpixel_position(params.seed, index, sample_index);
            vec3 dir = camera_direction(pixel, subpixel);
            // One call of path_radiance for hits and misses alike: gallivm runs both sides of
            // a branch, so two calls would run two copies of the path loop.
            RayHit hit;
            bool found = trace_closest(origin, dir, infinity(), hit);
            uint tri = found ? hit.triangle : 0u;
            vec3 ns = vec3(0.0);
            vec3 ng = vec3(0.0);
            uint mat = 0u;
            if (found) {
                ShadingTriangle st = shading_triangles[tri];
                ns = interpolated_normal(st, hit.barycentrics);
                ng = st.geometric_normal.xyz;
                mat = floatBitsToUint(st.n0.w);
            }
            // A non-finite sample is dropped whole (and counted) by accumulate_radiance.
            sum += path_radiance(index, sample_index, dir, found, origin + hit.t * dir,
                                 found ? hit.t : -1.0, tri, ns, ng, mat);
            ++k;
        } while (k < params.first_sample + params.sample_count);
        accumulate_radiance(index, sum / float(params.camera_samples));
    } else {
        GBufferTexel g = gbuffer[index];
        vec3 L = path_radiance(index, params.frame, g.direction.xyz, g.position.w >= 0.0,
                               g.position.xyz, g.position.w, floatBitsToUint(g.geometric_normal.w),
                               g.shading_normal.xyz, g.geometric_normal.xyz,
                               floatBitsToUint(g.shading_normal.w));
        accumulate_radiance(index, L);
    }
}
