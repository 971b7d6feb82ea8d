// ReSTIR DI's reservoirs and target function (Bitterli et al. 2020, "Spatiotemporal reservoir
// resampling for real-time ray tracing with dynamic direct lighting"), shared by
// glsl/restir/*.comp. A reservoir holds one light sample y (a light-table entry and a point
// on the light, the light's position, or a direction for the environment), its unbiased
// contribution weight W, its confidence M (the candidates behind it) and its target at its
// own surface. Invariant of every stored reservoir: W = 0 unless y is visible from the
// reservoir's own surface, so the target function reuse works with is p^ V (what ReSTIR calls
// visibility reuse) and shading needs no shadow ray of its own.
//
// Measures. p^(y) = Y(f Le cos_i G), G = cos_l / d^2 for a point on an emissive triangle (area
// measure), 1 for the environment (solid angle) and 1 / d^2 for a point or spot light (Le
// standing for the intensity): each sample's own measure is fixed by its light, so reservoirs
// of different pixels combine. Candidate weights are ratios of densities at one point, the same
// in either measure; W is in y's measure.
//
// Frames. Reuse in time evaluates the previous frame's reservoirs at the previous frame's
// surfaces (RestirPoint.previous): their target there is the one they were resampled for, so it
// takes the light as it was then. Within a render the lights and the light table stay put but the
// environment map may not (a sequence or the procedural sky shows map f mod n at frame f); across
// an animation's frames (the previous frame's reservoirs carried into this render, RTXDI's
// temporal reuse) the camera, the analytic lights, the emission and the map all may. So a
// previous-frame point reads the previous frame's materials' emission, lights and map
// (PreviousMaterials, PreviousLights, PreviousEnvTexels, defined by RESTIR_PREVIOUS_FRAME: the
// temporal pass), sees the previous camera, and a point or spot light sample is the light's
// position in whichever frame evaluates it (the sample is the light, identified by its entry,
// not a point in space). With this frame's map there instead, the balance heuristic's weights
// of the two domains no longer sum to one where the map changed: a sun that moved into a
// direction got the previous domain's share there, which cannot produce it, and 35% of a map
// sequence's light was lost (docs/DESIGN.md "State across frames").
//
// Bindings 13-15 (16-18 with RESTIR_PREVIOUS_FRAME; the temporal pass holds 19). Needs scene.glsl, sampling.glsl, bsdf.glsl,
// lights.glsl, gbuffer.glsl, and bvh.glsl unless RESTIR_NO_TRACE is defined (restir_visible
// left out).
#ifndef RESTIR_GLSL
#define RESTIR_GLSL

struct Reservoir {
    vec4 sample_point;  // xyz: the point on the light (emissive triangle), its position (point,
                        // spot) or the direction to it (environment); w bits: light entry
    vec4 weights;       // x: W, y: M, z: p^(y) at the reservoir's own surface, w: unused
};

// A pixel's surface of the previous frame (the G-buffer's is re-jittered every frame).
struct RestirSurface {
    vec4 position;  // xyz; w bits: material, 0xffffffff where the camera ray missed
    vec4 normal;    // shading normal on the viewer's side
    vec4 side;      // geometric normal on the viewer's side
};

// This frame's reservoirs: the candidates' after the temporal pass.
layout(set = 0, binding = 13, std430) buffer Reservoirs { Reservoir reservoirs[]; };
// Each frame's final reservoirs (after spatial reuse), what the next frame's temporal pass reuses.
layout(set = 0, binding = 14, std430) buffer FinalReservoirs { Reservoir final_reservoirs[]; };
layout(set = 0, binding = 15, std430) buffer PreviousSurfaces { RestirSurface previous_surfaces[]; };

#ifdef RESTIR_PREVIOUS_FRAME
// The environment's texels as the previous frame saw them: a sequence's frames, one after
// another (GpuScene::environment_texels_of), the live map when it is still, or the previous
// animation frame's map.
layout(set = 0, binding = 16, std430) readonly buffer PreviousEnvTexels {
    vec4 previous_env_texels[];
};
// The materials (their emission) and the analytic lights as the previous frame had them: this
// frame's own within a render, the previous animation frame's across frames.
layout(set = 0, binding = 17, std430) readonly buffer PreviousMaterials {
    Material previous_materials[];
};
layout(set = 0, binding = 18, std430) readonly buffer PreviousLights { Light previous_lights[]; };
// Where the previous frame's map starts in PreviousEnvTexels, and the camera position the
// previous frame's surfaces were seen from, set by the kernel from its push constants before
// any reuse.
uint restir_previous_env_base = 0u;
vec3 restir_previous_camera = vec3(0.0);
#endif

const uint NO_LIGHT = 0xffffffffu;

// A shading point as reuse sees it.
struct RestirPoint {
    vec3 p;
    vec3 n;     // shading normal, viewer's side
    vec3 side;  // geometric normal, viewer's side
    vec3 wo;    // toward the camera
    uint material;
    Material m; // loaded once (gallivm runs a storage-buffer load as a loop over the lanes);
                // untextured: the target functions' (shade_restir.comp textures it)
    bool valid;
    bool previous; // a surface of the previous frame, lit as the previous frame was
};

RestirPoint restir_point_from_gbuffer(uint pixel) {
    GBufferTexel g = gbuffer[pixel];
    RestirPoint s;
    s.valid = gbuffer_surface(g, s.wo, s.side, s.n);
    s.p = g.position.xyz;
    s.material = floatBitsToUint(g.shading_normal.w);
    s.m = materials[s.valid ? s.material : 0u];
    s.previous = false;
    return s;
}

// A surface stored by the previous frame's spatial pass (only the temporal pass reads them),
// seen from `camera` (the previous frame's camera position).
RestirPoint restir_point_from_surface(RestirSurface r, vec3 camera) {
    RestirPoint s;
    s.p = r.position.xyz;
    s.n = r.normal.xyz;
    s.side = r.side.xyz;
    s.material = floatBitsToUint(r.position.w);
    s.valid = s.material != NO_LIGHT;
    s.previous = true;
    s.m = materials[s.valid ? s.material : 0u];
    // Camera rays start at the camera's position (camera.glsl).
    vec3 to_camera = camera - s.p;
    float len2 = dot(to_camera, to_camera);
    s.wo = len2 > 0.0 ? to_camera * inversesqrt(len2) : s.n;
    return s;
}

RestirSurface restir_surface(RestirPoint s) {
    RestirSurface r;
    r.position = vec4(s.p, uintBitsToFloat(s.valid ? s.material : NO_LIGHT));
    r.normal = vec4(s.n, 0.0);
    r.side = vec4(s.side, 0.0);
    return r;
}

// The environment's radiance toward y as s's frame saw it.
vec3 restir_env_radiance(RestirPoint s, vec3 y) {
#ifdef RESTIR_PREVIOUS_FRAME
    if (s.previous) {
        return scene.env_size.z == 0u
            ? vec3(0.0) : previous_env_texels[restir_previous_env_base + env_texel_index(y)].rgb;
    }
#endif
    return env_radiance(y);
}

// Material `material`'s emitted radiance as s's frame saw it.
vec3 restir_emission(RestirPoint s, uint material) {
#ifdef RESTIR_PREVIOUS_FRAME
    if (s.previous) return previous_materials[material].ke.rgb;
#endif
    return materials[material].ke.rgb;
}

// Analytic light `index` as s's frame had it (where it stood, how bright).
Light restir_light(RestirPoint s, uint index) {
    // Member by member: glslang stores a block's struct into a local one of another block's
    // type (spirv-val rejects the OpStore).
#ifdef RESTIR_PREVIOUS_FRAME
    if (s.previous) {
        return Light(previous_lights[index].position, previous_lights[index].intensity,
                     previous_lights[index].direction, previous_lights[index].cone);
    }
#endif
    return Light(lights[index].position, lights[index].intensity, lights[index].direction,
                 lights[index].cone);
}

Reservoir empty_reservoir(float m) {
    Reservoir r;
    r.sample_point = vec4(0.0, 0.0, 0.0, uintBitsToFloat(NO_LIGHT));
    r.weights = vec4(0.0, m, 0.0, 0.0);
    return r;
}

// f Le cos_i G of light sample (entry, y) at s, in y's measure (see the header); zero where the
// light sends nothing toward s or s reflects nothing of it. wi and dist: toward the light (dist
// infinite for the environment); to_area: the factor that turns a solid-angle density at s into
// y's measure (cos_l / d^2 on a triangle, else 1).
vec3 restir_contribution(RestirPoint s, uint entry, vec3 y, out vec3 wi, out float dist,
                         out float to_area) {
    wi = vec3(0.0, 1.0, 0.0);
    dist = 0.0;
    to_area = 1.0;
    if (!s.valid || entry >= scene.size.z) return vec3(0.0);
    LightEntry e = light_entries[entry];
    vec3 le_g = vec3(0.0);
    if (SCENE_HAS_ENVIRONMENT && e.kind == 3u) {
        wi = y;
        dist = infinity();
        le_g = restir_env_radiance(s, y);
    } else {
        // A point or spot light is where s's frame has it (y is the light, not a place).
        Light l;
        if (SCENE_HAS_DELTA_LIGHTS && e.kind != 0u) {
            l = restir_light(s, e.index);
            y = l.position.xyz;
        }
        vec3 d = y - s.p;
        float dist2 = dot(d, d);
        if (!(dist2 > 0.0)) return vec3(0.0);
        dist = sqrt(dist2);
        wi = d / dist;
        if (e.kind == 0u) {
            EmitterTriangle t = emitter_triangles[e.index];
            float cos_light = -dot(wi, t.normal.xyz);
            if (cos_light <= 0.0) return vec3(0.0);
            to_area = cos_light / dist2;
            le_g = restir_emission(s, floatBitsToUint(t.normal.w)) * to_area;
        } else if (SCENE_HAS_DELTA_LIGHTS) {
            float falloff = e.kind == 2u ? spot_falloff(l, -wi) : 1.0;
            le_g = l.intensity.rgb * (falloff / dist2);
        }
    }
    float cos_i = dot(wi, s.n);
    if (cos_i <= 0.0 || dot(wi, s.side) <= 0.0) return vec3(0.0);
    return bsdf_eval(s.m, s.n, s.wo, wi) * cos_i * le_g;
}

float restir_target(RestirPoint s, uint entry, vec3 y) {
    vec3 wi;
    float dist, to_area;
    return luminance(restir_contribution(s, entry, y, wi, dist, to_area));
}

#ifndef RESTIR_NO_TRACE
// Whether light sample (entry, y) is visible from s (one shadow ray; the environment's toward
// direction y, a finite light's stopping just short of it).
bool restir_visible(RestirPoint s, uint entry, vec3 y) {
    if (!s.valid || entry >= scene.size.z) return false;
    LightEntry e = light_entries[entry];
    bool distant = SCENE_HAS_ENVIRONMENT && e.kind == 3u;
    if (SCENE_HAS_DELTA_LIGHTS && (e.kind == 1u || e.kind == 2u)) {
        y = restir_light(s, e.index).position.xyz;
    }
    vec3 origin = offset_origin(s.p, s.side);
    vec3 to_light = distant ? y : y - origin;
    return !trace_any(origin, to_light, distant ? infinity() : 0.9999);
}

// p^ V of (entry, y) at s: the target times the sample's visibility from s, a shadow ray only
// where p^ > 0. What the MIS weights of reuse see as the density of a reservoir's samples
// (restir.glsl's invariant: a stored reservoir's samples are visible from its surface).
float restir_visible_target(RestirPoint s, uint entry, vec3 y) {
    float target = restir_target(s, entry, y);
    return target > 0.0 && restir_visible(s, entry, y) ? target : 0.0;
}
#endif

// How reuse combines reservoirs (the push constants' `combination`; RestirSettings).
const uint COMBINATION_BIASED = 0u;     // 1 / (sum of M) (Alg. 4-5)
const uint COMBINATION_ONE_OVER_Z = 1u; // 1 / Z with visibility (Alg. 6)
const uint COMBINATION_MIS = 2u;        // the balance heuristic over p^ V (pairwise in space)

// The balance heuristic's share of a among a and b: a / (a + b), 0 where a is 0.
float balance_share(float a, float b) {
    return a > 0.0 ? a / (a + b) : 0.0;
}

// Streaming weighted selection (Bitterli et al. Alg. 2 without the M bookkeeping): candidate
// with weight w replaces the current choice with probability w / (sum so far).
bool reservoir_take(inout float weight_sum, float w, float u) {
    weight_sum += w;
    return w > 0.0 && u * weight_sum < w;
}

#endif
