// Albedo textures (src/scene/texture.rs, docs/DESIGN.md "Textures"), included by scene.glsl:
// one bilinear lookup, without mip levels, that every kernel shares, so a G-buffer texel, a
// VPL, a reverse VPL, a bundle hit and a path vertex all carry the same textured albedo.
// Storage buffers rather than sampled images: the filter is irad's own float arithmetic, the
// same on every device (a sampler's bilinear weights have implementation-defined precision:
// Vulkan's subTexelPrecisionBits may be as low as 4), and the CPU mirror
// `Texture::sample` reproduces it. Bindings 60-62.
#ifndef TEXTURE_GLSL
#define TEXTURE_GLSL

// Whether a material of the scene has a texture (src/scene/gpu.rs SceneFeatures): without one
// every lookup compiles out.
layout(constant_id = 3) const bool SCENE_HAS_TEXTURES = true;

#define NO_TEXTURE 0xffffffffu
#define WRAP_REPEAT 0u
#define WRAP_MIRROR 1u
#define WRAP_CLAMP 2u

// The texture coordinates over a triangle as affine functions of the point:
// u = origin.w + dot(du.xyz, p - origin.xyz), v = du.w + dot(dv.xyz, p - origin.xyz); from a
// point alone, so a stored point (a VPL, a G-buffer texel) needs only its triangle.
struct TriangleUv {
    vec4 origin; // xyz: corner 0; w: u at corner 0
    vec4 du;     // xyz: u's gradient in the triangle's plane; w: v at corner 0
    vec4 dv;     // xyz: v's gradient in the plane
};

layout(set = 0, binding = 60, std430) readonly buffer TriangleUvs { TriangleUv triangle_uvs[]; };
// Per material: x: its texture's first texel in texels[] (NO_TEXTURE: none), y: width,
// z: height, w: wrap across | wrap down << 2 (WRAP_*).
layout(set = 0, binding = 61, std430) readonly buffer MaterialTextures { uvec4 material_textures[]; };
// Linear RGB as half floats, rows from the top: x: r | g << 16, y: b.
layout(set = 0, binding = 62, std430) readonly buffer Texels { uvec2 texels[]; };

vec2 triangle_uv(uint triangle, vec3 p) {
    TriangleUv t = triangle_uvs[triangle];
    vec3 d = p - t.origin.xyz;
    return vec2(t.origin.w + dot(t.du.xyz, d), t.du.w + dot(t.dv.xyz, d));
}

// The continuous texel coordinate on one axis (u, or 1 - v: rows from the top), texel centres
// at half-integers; repeat reduces t mod 1, mirror mod 2; clamp's is clamped to [-1, n] so that
// a far coordinate stays an exact integer.
float texture_axis(float t, uint n, uint wrap) {
    if (wrap == WRAP_REPEAT) return (t - floor(t)) * float(n) - 0.5;
    if (wrap == WRAP_MIRROR) return (t - 2.0 * floor(0.5 * t)) * float(n) - 0.5;
    return clamp(t * float(n) - 0.5, -1.0, float(n));
}

uint texture_index(int i, uint n, uint wrap) {
    int m = int(n);
    if (wrap == WRAP_CLAMP) return uint(clamp(i, 0, m - 1));
    if (wrap == WRAP_REPEAT) return uint(((i % m) + m) % m);
    int k = ((i % (2 * m)) + 2 * m) % (2 * m);
    return uint(k < m ? k : 2 * m - 1 - k);
}

vec3 texel_rgb(uint i) {
    uvec2 t = texels[i];
    vec2 rg = unpackHalf2x16(t.x);
    return vec3(rg, unpackHalf2x16(t.y).x);
}

// The bilinear value of texture t at uv (OBJ's convention, v up).
vec3 sample_texture(uvec4 t, vec2 uv) {
    uint wrap_u = t.w & 3u, wrap_v = t.w >> 2;
    float x = texture_axis(uv.x, t.y, wrap_u);
    float y = texture_axis(1.0 - uv.y, t.z, wrap_v);
    float x0 = floor(x), y0 = floor(y);
    float fx = x - x0, fy = y - y0;
    uint i0 = texture_index(int(x0), t.y, wrap_u), i1 = texture_index(int(x0) + 1, t.y, wrap_u);
    uint r0 = t.x + texture_index(int(y0), t.z, wrap_v) * t.y;
    uint r1 = t.x + texture_index(int(y0) + 1, t.z, wrap_v) * t.y;
    vec3 top = texel_rgb(r0 + i0) * (1.0 - fx) + texel_rgb(r0 + i1) * fx;
    vec3 bottom = texel_rgb(r1 + i0) * (1.0 - fx) + texel_rgb(r1 + i1) * fx;
    return top * (1.0 - fy) + bottom * fy;
}

// Material m (materials[material]) at point p of triangle: its Kd times its texture there.
// The lobe probability kd.w stays the material's (any positive probability keeps the
// estimators unbiased).
// (`if (SCENE_HAS_TEXTURES)`, not a negation: glslang folds `!` of a specialization constant
// into an OpSpecConstantOp, which naga's reflection rejects.)
Material textured(Material m, uint material, uint triangle, vec3 p) {
    if (SCENE_HAS_TEXTURES) {
        uvec4 t = material_textures[material];
        if (t.x != NO_TEXTURE) m.kd.rgb *= sample_texture(t, triangle_uv(triangle, p));
    }
    return m;
}

// The material of triangle at its point p, textured.
Material surface_material(uint triangle, vec3 p) {
    uint material = triangle_material(triangle);
    return textured(materials[material], material, triangle, p);
}

#endif
