#version 450
// Keller 97 Section 3.2: the quasi-random walk that generates the VPLs. One invocation per
// path i of N; path i's numbers are scrambled Halton point i (halton.glsl), dimension
// allocation: 0 picks the light by power with the composition method (the number is rescaled
// within the chosen light's interval) and then, with 1, places the start point on it (the
// isometry of the unit square onto a triangle); 2-3 give the first direction (cosine about
// the emitter's normal; uniform over the sphere for a point light, over the falloff cone for
// a spot); vertex j >= 1 uses 4 + 3 (j - 1) .. 6 + 3 (j - 1): Phong lobe choice and the two
// direction numbers (cosine-distributed for the diffuse lobe, as Keller's). Dimensions past
// the 128 primes use the PCG hash.
//
// Absorption (VplSchedule, src/methods/ir/schedule.rs): Keller's fractional absorption for
// stills, where only paths i < N_j = floor(rho^j N) reach vertex j and a vertex-j VPL carries
// 1 / N_j of the path's throughput (Keller's compensation N / N_j with weight 1 / N); or
// Russian roulette for animation, each vertex surviving with probability rho (pseudo-random,
// as Keller says it must be), every path keeping a slot at every vertex. Where N_j reaches 0
// the paths still alive go on by roulette (irad's tail, unbiased where Keller's walk stops).
//
// Reuse across animation frames (ir's --reuse K, src/methods/ir/reuse.rs): a dispatch walks
// the paths i = path_phase (mod path_stride), one class, and leaves the others' slots; every
// walked path clears its own slots first. Path i takes Halton point i / path_stride under the
// class's own seed, so each class is a scrambled Halton set of its own (point i of one set
// split by i mod K would put a class's first numbers in one 1/K of [0, 1)).

#extension GL_GOOGLE_include_directive : require

layout(local_size_x = 64, local_size_y = 1, local_size_z = 1) in;

#define VPL_WRITE
#include "bvh.glsl"
#include "scene.glsl"
#include "sampling.glsl"
#include "halton.glsl"
#include "bsdf.glsl"
#include "lights.glsl"
#include "vpl.glsl"

// Per vertex j: x = N_j (paths that reach it), y = first VPL slot of vertex j, z = 1 when
// Russian roulette decides survival instead (then N_j = N, or in fractional absorption's
// tail the paths still alive at its last vertex), w = 1 in that tail.
layout(set = 0, binding = 14, std430) readonly buffer VplSchedule { uvec4 schedule[]; };

layout(push_constant) uniform WalkParams {
    uint path_count;     // N
    uint vertex_count;   // vertices per path, the light vertex included
    uint seed;           // scrambles the Halton digits and keys the roulette
    float survival;      // roulette: probability of going on at each vertex (mean albedo)
    uint path_stride;    // walks paths path_phase, path_phase + stride, ... (1: all)
    uint path_phase;
} params;

float walk_number(uint dimension, uint path) {
    uint index = path / params.path_stride;
    if (dimension < HALTON_DIMENSIONS) return halton(dimension, index, params.seed);
    return random(params.seed, index, 0x77616c6bu, dimension);
}

void write_vpl(uint vertex, uint path, Vpl v) {
    vpls[schedule[vertex].y + path] = v;
}

void main() {
    uint path = gl_GlobalInvocationID.x * params.path_stride + params.path_phase;
    if (path >= params.path_count) return;
    // The path's slots start empty (a path that ends early leaves its later ones so).
    Vpl empty;
    empty.position = vec4(0.0);
    empty.normal = vec4(0.0);
    empty.power = vec4(0.0);
    empty.incident = vec4(0.0);
    for (uint vertex = 0u; vertex < params.vertex_count; ++vertex) {
        // Path i has a slot at vertex j iff i < N_j (N under roulette, the paths still alive in
        // fractional absorption's tail).
        if (path < schedule[vertex].x) write_vpl(vertex, path, empty);
    }

    // Composition method: the light by power, then the same number rescaled inside it.
    float u0 = walk_number(0u, path);
    uint r = min(uint(u0 * 2147483648.0), 0x7fffffffu);
    uint entry_index = select_light(r);
    LightEntry e = light_entries[entry_index];
    uint lower = entry_index == 0u ? 0u : light_entries[entry_index - 1u].upper;
    float u_rescaled = clamp(float(r - lower) / float(e.upper - lower), 0.0, 0.99999994);
    vec2 u_point = vec2(u_rescaled, walk_number(1u, path));
    vec2 u_direction = vec2(walk_number(2u, path), walk_number(3u, path));

    float weight0 = 1.0 / float(schedule[0].x);
    vec3 origin;
    vec3 direction;
    vec3 beta;  // throughput from the light to the next vertex, divided by the light's pdfs
    Vpl v;
    if (e.kind == 0u) {
        EmitterTriangle t = emitter_triangles[e.index];
        vec2 b = sample_uniform_triangle(u_point);
        origin = t.p0.xyz + b.x * t.e1.xyz + b.y * t.e2.xyz;
        vec3 n = t.normal.xyz;
        vec3 le = materials[floatBitsToUint(t.normal.w)].ke.rgb;
        // Le cos / (p_select / A * cos / pi): the cosine cancels.
        beta = le * (PI * t.e2.w / e.probability);
        direction = to_world(sample_cosine_hemisphere(u_direction), n);
        origin = offset_origin(origin, n);
        v.position = vec4(origin, uintBitsToFloat(VPL_AREA));
        v.normal = vec4(n, 0.0);
        v.incident = vec4(n, 0.0);
    } else {
        Light l = lights[e.index];
        origin = l.position.xyz;
        if (e.kind == 2u) {
            // Uniform in the cone out to the falloff angle.
            float cos_falloff = l.direction.w;
            float cos_theta = mix(1.0, cos_falloff, u_direction.x);
            float sin_theta = sqrt(max(0.0, 1.0 - cos_theta * cos_theta));
            float phi = 2.0 * PI * u_direction.y;
            direction = to_world(vec3(sin_theta * cos(phi), sin_theta * sin(phi), cos_theta),
                                 l.direction.xyz);
            float solid_angle = 2.0 * PI * (1.0 - cos_falloff);
            beta = l.intensity.rgb * (spot_falloff(l, direction) * solid_angle / e.probability);
            v.position = vec4(origin, uintBitsToFloat(VPL_SPOT));
            v.normal = vec4(l.direction.xyz, cos_falloff);
        } else {
            float z = 1.0 - 2.0 * u_direction.x;
            float s = sqrt(max(0.0, 1.0 - z * z));
            float phi = 2.0 * PI * u_direction.y;
            direction = vec3(s * cos(phi), s * sin(phi), z);
            beta = l.intensity.rgb * (4.0 * PI / e.probability);
            v.position = vec4(origin, uintBitsToFloat(VPL_POINT));
            v.normal = vec4(0.0);
        }
        v.incident = vec4(0.0);
    }
    // The light vertex (shaded only with --direct vpl): an area light's start point carries its
    // share of the flux, Le pi A / p_select / N; a point or spot light's its share of the
    // intensity, I / p_select / N (the falloff is applied when shading).
    if (e.kind == 0u) {
        v.power = vec4(beta * weight0, 0.0);
    } else {
        Light l = lights[e.index];
        v.power = vec4(l.intensity.rgb * (weight0 / e.probability), l.cone.x);
    }
    write_vpl(0u, path, v);

    for (uint vertex = 1u; vertex < params.vertex_count; ++vertex) {
        uvec4 level = schedule[vertex];
        bool roulette = level.z != 0u;
        if (!roulette && path >= level.x) break;
        if (max(max(beta.r, beta.g), beta.b) <= 0.0) break;

        RayHit hit;
        if (!trace_closest(origin, direction, infinity(), hit)) break;
        vec3 p = origin + hit.t * direction;
        vec3 ng = shading_triangles[hit.triangle].geometric_normal.xyz;
        vec3 ns = shading_normal(hit.triangle, hit.barycentrics);
        vec3 wo = -direction;
        vec3 side = dot(wo, ng) >= 0.0 ? ng : -ng;
        vec3 n = dot(ns, side) >= 0.0 ? ns : -ns;
        uint mat = triangle_material(hit.triangle);

        Vpl s;
        s.position = vec4(p, uintBitsToFloat(VPL_SURFACE));
        s.normal = vec4(n, uintBitsToFloat(mat));
        // w: the triangle hit (reweigh_vpls.comp reads its geometric normal).
        s.power = vec4(beta / float(level.x), uintBitsToFloat(hit.triangle));
        s.incident = vec4(wo, 0.0);
        write_vpl(vertex, path, s);

        // Scatter on: the BSDF at the vertex, sampled with this vertex's Halton numbers.
        Material m = textured(materials[mat], mat, hit.triangle, p);
        uint dim = 4u + 3u * (vertex - 1u);
        vec3 u = vec3(walk_number(dim, path), walk_number(dim + 1u, path),
                      walk_number(dim + 2u, path));
        vec3 wi;
        if (!bsdf_sample(m, n, wo, u, wi)) break;
        float pdf = bsdf_pdf(m, n, wo, wi);
        float cos_i = dot(wi, n);
        if (pdf <= 0.0 || cos_i <= 0.0 || dot(wi, side) <= 0.0) break;
        vec3 scatter = bsdf_eval(m, n, wo, wi) * (cos_i / pdf);
        beta *= scatter;
        // Fractional absorption: the next vertex's compensation N_j / N_{j+1} is applied
        // through the slot weight 1 / N_{j+1}; roulette divides by the survival probability:
        // Keller's rho, or in fractional absorption's tail (level.w = 1) the scattering
        // weight's largest channel, so the surviving throughput stays bounded.
        if (roulette) {
            float survival = level.w != 0u
                ? clamp(max(max(scatter.r, scatter.g), scatter.b), 0.05, 1.0)
                : params.survival;
            if (random(params.seed, path, 0x72722121u, vertex) >= survival) break;
            beta /= survival;
        }
        origin = offset_origin(p, side);
        direction = wi;
    }
}
