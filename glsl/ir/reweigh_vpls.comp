#version 450
// ir's VPL reuse across animation frames (--reuse K, src/methods/ir/reuse.rs): the paths of
// trace_vpls.comp fall into K classes, path i in class i mod K, and each animation frame walks
// one class afresh (the walk's VPL slots, BaseVpls, keep the other classes' slots as the
// frame that walked them left them). This pass writes the frame's VPLs (Vpls) from BaseVpls,
// each path re-weighed for this frame's lights. One invocation per path.
//
// Where a point or spot light moved (Laine et al. 07's incremental instant radiosity keeps the
// VPLs still visible from the light where it is now; Keller 97's Russian roulette makes each
// path an independent sample that can be kept), a kept path (y, x1, x2, ...) is re-weighed so
// that the K classes together stay an unbiased estimate of this frame's light, by multiple
// importance sampling over the classes with the balance heuristic on the first vertex:
//
//   VPL power at vertex j = f(y_now -> x1) T_rest / sum_k n_kj p_k(x1)
//
// where p_k(x1) is the area density of x1 as the first hit from the light where class k's frame
// had it (its direction density, cos at x1 / d^2, and visibility: a shadow ray), n_kj the class
// k paths that have a slot at vertex j (fractional absorption's N_j split by class), f the
// emitted intensity toward x1 times cos / d^2 and the visibility from where the light is now,
// and T_rest the rest of the path's throughput as walked. A kept path hidden from the light now
// carries nothing (Laine's invalid VPL) and this frame's fresh class covers what it no longer
// reaches, so nothing is lost where the light uncovers new surfaces; the price is variance
// there (only n / K paths can reach them). With nothing moved every p_k is the same and every
// factor is 1. The BSDF at x1, which the incident direction changes, is re-evaluated for the
// vertices past it (exact where the lobe walked at x1 covers the new one: always for diffuse
// surfaces). The selection probability of the light is the same in every class
// (src/methods/ir/reuse.rs keeps paths only while the light table is unchanged) and cancels.
// The light vertex (shaded with --direct vpl) moves with its light; an area light's paths are
// copied as walked (area lights stand still, and their emission is unchanged while paths are
// kept).

#extension GL_GOOGLE_include_directive : require

layout(local_size_x = 64, local_size_y = 1, local_size_z = 1) in;

#define VPL_NO_BUFFER
#include "bvh.glsl"
#include "scene.glsl"
#include "sampling.glsl"
#include "halton.glsl"
#include "bsdf.glsl"
#include "lights.glsl"
#include "vpl.glsl"

layout(set = 0, binding = 13, std430) writeonly buffer Vpls { Vpl vpls[]; };
// trace_vpls.comp's schedule: per vertex j, x = N_j, y = first slot, z = 1 under roulette.
layout(set = 0, binding = 14, std430) readonly buffer VplSchedule { uvec4 schedule[]; };
layout(set = 0, binding = 15, std430) readonly buffer BaseVpls { Vpl base_vpls[]; };
// Per class k: the analytic lights as the frame that walked class k had them, light l at
// k * light_count + l.
layout(set = 0, binding = 16, std430) readonly buffer ClassLights { Light class_lights[]; };
// Per class k: the seed of the walk that made it (its paths' Halton scramble).
layout(set = 0, binding = 17, std430) readonly buffer ClassSeeds { uint class_seeds[]; };

layout(push_constant) uniform ReweighParams {
    uint path_count;     // N
    uint vertex_count;   // schedule levels
    uint classes;        // K (at most MAX_CLASSES)
    uint light_count;    // analytic lights per class
    uint fresh;          // the class walked this frame (its lights are this frame's)
} params;

const uint MAX_CLASSES = 16u;

// The walk's density of emitting toward `dir` (unit, from the light): uniform over the sphere
// for a point light, over the falloff cone for a spot (trace_vpls.comp).
float emission_pdf(Light l, uint kind, vec3 dir) {
    if (kind == 2u) {
        float cos_falloff = l.direction.w;
        if (dot(dir, l.direction.xyz) < cos_falloff) return 0.0;
        return 1.0 / (2.0 * PI * (1.0 - cos_falloff));
    }
    return 1.0 / (4.0 * PI);
}

// The intensity's angular factor toward `dir` (the intensity itself is the same in every class).
float emission_shape(Light l, uint kind, vec3 dir) {
    return kind == 2u ? spot_falloff(l, dir) : 1.0;
}

// Path i has a slot at vertex j iff i < N_j (trace_vpls.comp).
bool slot_exists(uvec4 level, uint path) {
    return path < level.x;
}

void main() {
    uint path = gl_GlobalInvocationID.x;
    if (path >= params.path_count) return;
    uint own = path % params.classes;

    uint slot0 = schedule[0].y + path;
    Vpl v0 = base_vpls[slot0];
    uint kind0 = vpl_kind(v0);
    bool analytic = kind0 == VPL_POINT || kind0 == VPL_SPOT;
    bool has_x1 = params.vertex_count > 1u && slot_exists(schedule[1], path) &&
                  vpl_kind(base_vpls[schedule[1].y + path]) != VPL_NONE;
    if (!analytic || own == params.fresh) {
        // An area light's path, or one walked this frame: as walked, unless reweighed below
        // (a fresh path's weight depends on the kept classes too).
        if (!analytic || !has_x1) {
            for (uint vertex = 0u; vertex < params.vertex_count; ++vertex) {
                uvec4 level = schedule[vertex];
                if (!slot_exists(level, path)) break;
                vpls[level.y + path] = base_vpls[level.y + path];
            }
            return;
        }
    }

    // The path's light, chosen again as the walk chose it (its first Halton number under its
    // class's seed; the table is the same in every class).
    float u0 = halton(0u, path / params.classes, class_seeds[own]);
    uint r = min(uint(u0 * 2147483648.0), 0x7fffffffu);
    LightEntry e = light_entries[select_light(r)];
    if (e.kind == 0u) {
        // Not the walk's choice (it cannot differ, but an area light's entry must not index
        // the analytic lights): the path as walked.
        for (uint vertex = 0u; vertex < params.vertex_count; ++vertex) {
            uvec4 level = schedule[vertex];
            if (!slot_exists(level, path)) break;
            vpls[level.y + path] = base_vpls[level.y + path];
        }
        return;
    }
    Light now = lights[e.index];
    // The light vertex where its light is now.
    v0.position.xyz = now.position.xyz;
    if (kind0 == VPL_SPOT) v0.normal.xyz = now.direction.xyz;
    vpls[slot0] = v0;
    if (!has_x1) {
        for (uint vertex = 1u; vertex < params.vertex_count; ++vertex) {
            uvec4 level = schedule[vertex];
            if (!slot_exists(level, path)) break;
            vpls[level.y + path] = base_vpls[level.y + path];
        }
        return;
    }

    Vpl x1 = base_vpls[schedule[1].y + path];
    vec3 p1 = x1.position.xyz;
    vec3 n1 = x1.normal.xyz;  // shading normal, on the side the walk's light lit
    // The geometric normal on the side the walked light lit (the walk's rule): the area
    // density's cosine and the offset.
    Light walked = class_lights[own * params.light_count + e.index];
    vec3 d_gen = p1 - walked.position.xyz;
    float dist2_gen = dot(d_gen, d_gen);
    vec3 dir_gen = d_gen * inversesqrt(dist2_gen);
    vec3 ng = shading_triangles[floatBitsToUint(x1.power.w)].geometric_normal.xyz;
    if (dot(-dir_gen, ng) < 0.0) ng = -ng;
    vec3 target = offset_origin(p1, ng);

    // p_k(x1) for each class. The path's own class, and any class whose light stood where its
    // did, saw x1 as its first hit; another is tested from its light toward x1, as the walk
    // found x1.
    float density[MAX_CLASSES];
    for (uint k = 0u; k < params.classes; ++k) {
        Light lk = class_lights[k * params.light_count + e.index];
        bool same = lk.position.xyz == walked.position.xyz &&
                    (e.kind != 2u || lk.direction.xyz == walked.direction.xyz);
        vec3 d = p1 - lk.position.xyz;
        float dist2 = dot(d, d);
        float pk = 0.0;
        if (dist2 > 0.0) {
            vec3 dir = d * inversesqrt(dist2);
            float cos1 = -dot(dir, ng);
            if (cos1 > 0.0) pk = emission_pdf(lk, e.kind, dir) * cos1 / dist2;
            if (pk > 0.0 && !same &&
                trace_any(lk.position.xyz, target - lk.position.xyz, 0.9999)) pk = 0.0;
        }
        density[k] = pk;
    }

    // f(y -> x1) up to the intensity, as walked and now (visible now where the fresh class,
    // whose light is this frame's, sees x1).
    float f_gen = emission_shape(walked, e.kind, dir_gen) * (-dot(dir_gen, ng)) / dist2_gen;
    vec3 d_now = p1 - now.position.xyz;
    float dist2_now = dot(d_now, d_now);
    vec3 dir_now = d_now * inversesqrt(max(dist2_now, 1e-30));
    float f_now = density[params.fresh] > 0.0
        ? emission_shape(now, e.kind, dir_now) * (-dot(dir_now, ng)) / dist2_now
        : 0.0;
    float ratio = f_gen > 0.0 ? f_now / f_gen : 0.0;

    // The BSDF at x1 toward x2 for the vertices past it, as walked and now.
    vec3 bsdf_ratio = vec3(1.0);
    uint mat1 = floatBitsToUint(x1.normal.w);
    Material m1 = textured(materials[mat1], mat1, floatBitsToUint(x1.power.w), p1);
    bool glossy = SCENE_HAS_GLOSSY && max(max(m1.ks.r, m1.ks.g), m1.ks.b) > 0.0;
    if (glossy && params.vertex_count > 2u && slot_exists(schedule[2], path)) {
        Vpl x2 = base_vpls[schedule[2].y + path];
        if (vpl_kind(x2) != VPL_NONE && ratio > 0.0) {
            vec3 wi = normalize(x2.position.xyz - p1);
            vec3 f_walked = bsdf_eval(m1, n1, x1.incident.xyz, wi);
            vec3 f_now3 = bsdf_eval(m1, n1, -dir_now, wi);
            bsdf_ratio = vec3(f_walked.r > 0.0 ? f_now3.r / f_walked.r : 0.0,
                              f_walked.g > 0.0 ? f_now3.g / f_walked.g : 0.0,
                              f_walked.b > 0.0 ? f_now3.b / f_walked.b : 0.0);
        }
    }

    for (uint vertex = 1u; vertex < params.vertex_count; ++vertex) {
        uvec4 level = schedule[vertex];
        if (!slot_exists(level, path)) break;
        Vpl s = base_vpls[level.y + path];
        // sum_k n_kj p_k: class k's paths below N_j (all N under roulette).
        float mixture = 0.0;
        for (uint k = 0u; k < params.classes; ++k) {
            uint n_k = k < level.x ? (level.x - k + params.classes - 1u) / params.classes : 0u;
            mixture += float(n_k) * density[k];
        }
        // The walk stored T / N_j; T_rest f_now / sum_k n_kj p_k is its
        // N_j p_own / f_gen f_now / sum_k n_kj p_k times that.
        float scale = mixture > 0.0 ? float(level.x) * density[own] * ratio / mixture : 0.0;
        vec3 factor = vec3(scale) * (vertex >= 2u ? bsdf_ratio : vec3(1.0));
        s.power.rgb *= factor;
        if (vertex == 1u && ratio > 0.0) s.incident.xyz = -dir_now;
        vpls[level.y + path] = s;
    }
}
