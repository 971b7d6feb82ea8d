// The scene as every method's kernels see it (src/scene/gpu.rs uploads it): shading data per
// triangle in BVH order, materials, analytic lights, the light-selection table, emissive
// triangles, the environment map and its CDF, the scene constants, and the albedo textures
// (texture.glsl). Bindings 2-9 and 60-62 (bvh.glsl holds 0, 1 and 63); kernels number their
// own from 10.
#ifndef SCENE_GLSL
#define SCENE_GLSL

struct ShadingTriangle {
    vec4 n0;               // shading normal at corner 0; w: material index (uint bits)
    vec4 n1;               // corner 1; w: probability that light selection picks this triangle
    vec4 n2;               // corner 2; w: area
    vec4 geometric_normal; // unit, counter-clockwise side; w bits: an emissive triangle's
                           // entry in LightEntries (0xffffffff for every other triangle)
};

struct Material {
    vec4 kd;    // diffuse albedo; w: probability of sampling the Phong lobe
    vec4 ks;    // Phong albedo; w: Phong exponent
    vec4 ke;    // emitted radiance; w: 1 when emissive
};

// kind: 0 emissive triangle (index: EmitterTriangles entry), 1 point, 2 spot (index: Lights entry),
// 3 environment. upper: exclusive upper bound of the entry's range of 31-bit random integers
// (src/sampling/distribution.rs); probability: the realised (upper - previous upper) / 2^31.
struct LightEntry {
    uint kind;
    uint index;
    float probability;
    uint upper;
};

struct Light {
    vec4 position;   // w: kind (1 point, 2 spot)
    vec4 intensity;  // W/sr
    vec4 direction;  // spot axis (unit); w: cos(falloff_angle)
    vec4 cone;       // x: cos(cone_angle)
};

struct EmitterTriangle {
    vec4 p0;
    vec4 e1;
    vec4 e2;       // w: area
    vec4 normal;   // unit geometric normal (the emitting side); w: material index (uint bits)
};

struct SceneConstants {
    vec4 camera_position; // w: tan(fov_y / 2)
    vec4 camera_forward;  // w: width / height
    vec4 camera_right;
    vec4 camera_up;
    uvec4 size;           // image width, height, light entry count, triangle count
    uvec4 env_size;       // environment width, height, 1 when present
    vec4 env;             // x: probability of selecting the environment
    vec4 bounds;          // xyz: scene centre, w: scene radius
};

layout(set = 0, binding = 2, std430) readonly buffer ShadingTriangles { ShadingTriangle shading_triangles[]; };
layout(set = 0, binding = 3, std430) readonly buffer Materials { Material materials[]; };
layout(set = 0, binding = 4, std430) readonly buffer Lights { Light lights[]; };
layout(set = 0, binding = 5, std430) readonly buffer LightEntries { LightEntry light_entries[]; };
layout(set = 0, binding = 6, std430) readonly buffer EmitterTriangles { EmitterTriangle emitter_triangles[]; };
// rgb: radiance; w: solid-angle pdf of env_sample in this texel (realised texel probability
// over the texel's solid angle).
layout(set = 0, binding = 7, std430) readonly buffer EnvTexels { vec4 env_texels[]; };
// Exclusive upper bounds of each texel's range of 31-bit random integers.
layout(set = 0, binding = 8, std430) readonly buffer EnvCdf { uint env_cdf[]; };
// A uniform block: gallivm loads its fields once per subgroup, where a storage buffer's load is
// a loop over the lanes (the reference on the Cornell box, lavapipe: 1.09x).
layout(set = 0, binding = 9, std140) uniform SceneParams { SceneConstants scene; };

// What the scene holds, as specialization constants (src/scene/gpu.rs SceneFeatures): a
// kernel specialized for a scene compiles out the code of what it lacks. gallivm (lavapipe)
// runs both sides of every branch, taken or not, so code for an absent light type or lobe
// costs every invocation its full time; the defaults (true) keep every path for kernels built
// without specialization. Measured on the reference, Cornell box 256x256, lavapipe: 1.13x.
layout(constant_id = 0) const bool SCENE_HAS_ENVIRONMENT = true;
layout(constant_id = 1) const bool SCENE_HAS_DELTA_LIGHTS = true;  // point or spot lights
layout(constant_id = 2) const bool SCENE_HAS_GLOSSY = true;        // any Phong lobe (Ks > 0)

uint triangle_material(uint triangle) {
    return floatBitsToUint(shading_triangles[triangle].n0.w);
}

#include "texture.glsl"

// The interpolated shading normal of t at barycentrics uv.
vec3 interpolated_normal(ShadingTriangle t, vec2 uv) {
    vec3 n = (1.0 - uv.x - uv.y) * t.n0.xyz + uv.x * t.n1.xyz + uv.y * t.n2.xyz;
    float len2 = dot(n, n);
    return len2 > 1e-20 ? n * inversesqrt(len2) : t.geometric_normal.xyz;
}

vec3 shading_normal(uint triangle, vec2 uv) {
    return interpolated_normal(shading_triangles[triangle], uv);
}

// Offsets a ray origin off the surface on the side of `side_normal`, in proportion to the
// point's coordinates (float rounding of a hit grows with them), with a floor of 1e-6 of the
// scene radius near the origin.
vec3 offset_origin(vec3 p, vec3 side_normal) {
    float scale = max(max(abs(p.x), abs(p.y)), max(abs(p.z), 0.01 * scene.bounds.w));
    return p + side_normal * (1e-4 * scale);
}

#endif
