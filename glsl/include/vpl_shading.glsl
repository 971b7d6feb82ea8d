// One VPL's contribution to a shading point (Keller 97's point-light shading): the BSDF at
// both ends, the geometry term (optionally clamped: Keller's weak singularity) and one any-hit
// shadow ray. Shared by accumulate_vpls_tiled.comp and shade_reverse_vpls.comp. Needs
// bvh.glsl, scene.glsl, bsdf.glsl, lights.glsl and vpl.glsl.
#ifndef VPL_SHADING_GLSL
#define VPL_SHADING_GLSL

// A surface VPL's material at its point, textured (texture.glsl); material 0 for the other
// kinds, which do not read it. Kernels that shade many points from one VPL look it up once
// (accumulate_vpls_tiled.comp keeps it beside the VPL in shared memory): looked up per pair,
// two textured materials made ir 1.3x slower, once per VPL 1.04x (docs/DESIGN.md
// "Textures" has the measurement).
Material vpl_material(Vpl v) {
    bool surface = vpl_kind(v) == VPL_SURFACE;
    uint material = surface ? floatBitsToUint(v.normal.w) : 0u;
    uint triangle = surface ? floatBitsToUint(v.power.w) : 0u;
    return textured(materials[material], material, triangle, v.position.xyz);
}

// v and mv (vpl_material(v)): the VPL; x: the shading point; origin: x offset off its
// surface; n: shading normal on the side of wo; side: geometric normal on that side; m: the
// material at x. g_clamp 0: no clamp.
vec3 shade_from_vpl(Vpl v, Material mv, vec3 x, vec3 origin, vec3 n, vec3 side, vec3 wo,
                    Material m, float g_clamp) {
    uint kind = vpl_kind(v);
    if (kind == VPL_NONE) return vec3(0.0);
    vec3 d = v.position.xyz - x;
    float dist2 = dot(d, d);
    if (dist2 <= 0.0) return vec3(0.0);
    vec3 w = d * inversesqrt(dist2);
    float cos_x = dot(n, w);
    if (cos_x <= 0.0 || dot(side, w) <= 0.0) return vec3(0.0);
    vec3 fx = bsdf_eval(m, n, wo, w);
    if (max(max(fx.r, fx.g), fx.b) <= 0.0) return vec3(0.0);

    // Emitted toward x per unit G, and G = cos_v cos_x / d^2 (cos_v = 1 for point lights).
    vec3 emitted;
    float cos_v = 1.0;
    vec3 target = v.position.xyz;
    if (kind == VPL_SURFACE) {
        cos_v = dot(v.normal.xyz, -w);
        if (cos_v <= 0.0) return vec3(0.0);
        emitted = v.power.rgb * bsdf_eval(mv, v.normal.xyz, v.incident.xyz, -w);
        target = offset_origin(target, v.normal.xyz);
    } else if (kind == VPL_AREA) {
        cos_v = dot(v.normal.xyz, -w);
        if (cos_v <= 0.0) return vec3(0.0);
        emitted = v.power.rgb * INV_PI;
    } else if (kind == VPL_SPOT) {
        Light l;
        l.direction = v.normal;
        l.cone = vec4(v.power.w, 0.0, 0.0, 0.0);
        emitted = v.power.rgb * spot_falloff(l, -w);
    } else {
        emitted = v.power.rgb;
    }
    float g = cos_v * cos_x / dist2;
    if (g_clamp > 0.0) g = min(g, g_clamp);
    vec3 contribution = emitted * fx * g;
    if (max(max(contribution.r, contribution.g), contribution.b) <= 0.0) return vec3(0.0);
    if (trace_any(origin, target - origin, 0.9999)) return vec3(0.0);
    return contribution;
}

#endif
