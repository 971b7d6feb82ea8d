// Light selection through the light BVH (pbrt-v4's BVHLightSampler, Pharr et al. 2023
// Section 12.6.3; Conty and Kulla 2018), built on the CPU once per scene
// (src/sampling/light_bvh.rs, which also holds the f32 mirror of every function here). The
// environment map is chosen apart, with its share of the power table (the last entry of
// LightEntries); the other lights descend the tree: at each node the two children's importance
// (power times a bound on the emitter's cosine over the squared distance, times a bound on the
// receiver's cosine) chooses the child, the random number remapped into it (pbrt's
// SampleDiscrete), so one number serves the whole descent. The pmf of a given light re-walks
// its bit trail (LightTrails), as MIS needs when a BSDF-sampled ray hits an emitter.
//
// Nodes are 32 bytes (two loads), depth-first (child 0 right after its parent, child 1 at the
// index the parent stores), so the descent needs no stack; it is at most 64 levels (the
// build's bound), a loop of at most 64 iterations. Bindings 37 and 38. Needs scene.glsl and lights.glsl.
#ifndef LIGHT_BVH_GLSL
#define LIGHT_BVH_GLSL

struct LightNode {
    vec4 sphere;  // xyz: the centre of a sphere around the node's lights; w: its radius
    vec4 packed;  // x: phi (the lights' power); bits of y: child 1's index, or the light's
                  // entry | 0x80000000 (leaf); of z: the cone's axis (octahedral_decode); of w:
                  // cos theta_o (low half) and cos theta_e (high half), half floats rounded down
};

layout(set = 0, binding = 37, std430) readonly buffer LightBvhNodes { LightNode light_nodes[]; };
// Per light-table entry: its bit trail (x: depths 0-31, y: 32-63; bit d set where the path to
// its leaf takes child 1 at depth d).
layout(set = 0, binding = 38, std430) readonly buffer LightTrails { uvec2 light_trails[]; };

const uint LIGHT_LEAF = 0x80000000u;
const uint LIGHT_BVH_MAX_DEPTH = 64u;
const float ONE_MINUS_EPSILON = 0.99999994;

float cos_sub_clamped(float sin_a, float cos_a, float sin_b, float cos_b) {
    return cos_a > cos_b ? 1.0 : cos_a * cos_b + sin_a * sin_b;
}

float sin_sub_clamped(float sin_a, float cos_a, float sin_b, float cos_b) {
    return cos_a > cos_b ? 0.0 : sin_a * cos_b - cos_a * sin_b;
}

float safe_sqrt(float x) {
    return sqrt(max(x, 0.0));
}

// The axis of an octahedral vector (two snorm16: x low, y high), as
// src/sampling/light_bvh.rs `octahedral_decode` computes it (divisions and square roots, which
// are exact, so the CPU mirror gets the same bits).
vec3 octahedral_decode(uint bits) {
    const float SCALE = 1.0 / 32767.0;
    float x = max(float(int(bits << 16u) >> 16) * SCALE, -1.0);
    float y = max(float(int(bits) >> 16) * SCALE, -1.0);
    vec3 v = vec3(x, y, 1.0 - abs(x) - abs(y));
    if (v.z < 0.0) {
        v.x = (1.0 - abs(y)) * (x >= 0.0 ? 1.0 : -1.0);
        v.y = (1.0 - abs(x)) * (y >= 0.0 ? 1.0 : -1.0);
    }
    return v / sqrt(dot(v, v));
}

// pbrt's LightBounds::Importance of node `nd` at point p with normal n (zero: none).
float light_importance(LightNode nd, vec3 p, vec3 n) {
    vec3 pc = nd.sphere.xyz;
    float radius = nd.sphere.w;
    float phi = nd.packed.x;
    vec3 to_p = p - pc;
    float dist2 = dot(to_p, to_p);
    // pbrt clamps d^2 below by half the diagonal's length (not its square): here the radius.
    float d2 = max(dist2, radius);
    vec3 wi = dist2 > 0.0 ? to_p / sqrt(dist2) : vec3(0.0, 0.0, 1.0);
    float cos_theta_w = dot(octahedral_decode(floatBitsToUint(nd.packed.z)), wi);
    float sin_theta_w = safe_sqrt(1.0 - cos_theta_w * cos_theta_w);
    float r2 = radius * radius;
    float cos_theta_b = dist2 < r2 ? -1.0 : safe_sqrt(1.0 - r2 / dist2);
    float sin_theta_b = safe_sqrt(1.0 - cos_theta_b * cos_theta_b);
    vec2 cosines = unpackHalf2x16(floatBitsToUint(nd.packed.w));
    float cos_theta_o = cosines.x;
    float sin_theta_o = safe_sqrt(1.0 - cos_theta_o * cos_theta_o);
    float cos_theta_x = cos_sub_clamped(sin_theta_w, cos_theta_w, sin_theta_o, cos_theta_o);
    float sin_theta_x = sin_sub_clamped(sin_theta_w, cos_theta_w, sin_theta_o, cos_theta_o);
    float cos_theta_p = cos_sub_clamped(sin_theta_x, cos_theta_x, sin_theta_b, cos_theta_b);
    // Zero strictly beyond the falloff (pbrt tests <=): a hard-edged spot has cos theta_e = 1
    // and cos theta' = 1 inside its cone, which <= would count as outside.
    if (cos_theta_p < cosines.y) return 0.0;
    float importance = phi * cos_theta_p / d2;
    if (n != vec3(0.0)) {
        float cos_theta_i = abs(dot(wi, n));
        float sin_theta_i = safe_sqrt(1.0 - cos_theta_i * cos_theta_i);
        importance *= cos_sub_clamped(sin_theta_i, cos_theta_i, sin_theta_b, cos_theta_b);
    }
    return max(importance, 0.0);
}

// Descends from the root with u in [0, 1): the chosen light's entry and its pmf within the
// tree; false where no light can reach (p, n).
bool light_bvh_select(vec3 p, vec3 n, float u, out uint entry, out float pmf) {
    entry = 0u;
    pmf = 0.0;
    LightNode nd = light_nodes[0];
    uint link = floatBitsToUint(nd.packed.y);
    if ((link & LIGHT_LEAF) != 0u) {
        entry = link & ~LIGHT_LEAF;
        pmf = 1.0;
        return light_importance(nd, p, n) > 0.0;
    }
    uint node = 0u;
    float product = 1.0;
    for (uint level = 0u; level < LIGHT_BVH_MAX_DEPTH; ++level) {
        uint c0 = node + 1u;
        uint c1 = link;
        LightNode n0 = light_nodes[c0];
        LightNode n1 = light_nodes[c1];
        float i0 = light_importance(n0, p, n);
        float i1 = light_importance(n1, p, n);
        if (!(i0 > 0.0 || i1 > 0.0)) return false;
        float sum = i0 + i1;
        float t = u * sum;
        bool first = t < i0 || !(i1 > 0.0);
        product *= (first ? i0 : i1) / sum;
        u = min(first ? t / i0 : (t - i0) / i1, ONE_MINUS_EPSILON);
        node = first ? c0 : c1;
        link = floatBitsToUint(first ? n0.packed.y : n1.packed.y);
        if ((link & LIGHT_LEAF) != 0u) {
            entry = link & ~LIGHT_LEAF;
            pmf = product;
            return true;
        }
    }
    return false;
}

// The pmf with which light_bvh_select picks `entry` at (p, n): its bit trail re-walked.
float light_bvh_pmf(vec3 p, vec3 n, uint entry) {
    LightNode nd = light_nodes[0];
    uint link = floatBitsToUint(nd.packed.y);
    if ((link & LIGHT_LEAF) != 0u) {
        return (link & ~LIGHT_LEAF) == entry && light_importance(nd, p, n) > 0.0 ? 1.0 : 0.0;
    }
    uvec2 trail = light_trails[entry];
    uint node = 0u;
    float product = 1.0;
    for (uint level = 0u; level < LIGHT_BVH_MAX_DEPTH; ++level) {
        uint c0 = node + 1u;
        uint c1 = link;
        LightNode n0 = light_nodes[c0];
        LightNode n1 = light_nodes[c1];
        float i0 = light_importance(n0, p, n);
        float i1 = light_importance(n1, p, n);
        if (!(i0 > 0.0 || i1 > 0.0)) return 0.0;
        uint bits = level < 32u ? trail.x : trail.y;
        bool first = ((bits >> (level & 31u)) & 1u) == 0u;
        product *= (first ? i0 : i1) / (i0 + i1);
        node = first ? c0 : c1;
        link = floatBitsToUint(first ? n0.packed.y : n1.packed.y);
        if ((link & LIGHT_LEAF) != 0u) {
            return (link & ~LIGHT_LEAF) == entry ? product : 0.0;
        }
    }
    return 0.0;
}

// The upper bound of the entries the tree holds (every entry but the environment, the last):
// their share of the power table is this over 2^31, and r_select at or above it picks the
// environment, as the power table would.
uint light_bvh_bound() {
    uint count = scene.size.z;
    if (SCENE_HAS_ENVIRONMENT && scene.env.x > 0.0) {
        return count <= 1u ? 0u : light_entries[count - 2u].upper;
    }
    return count == 0u ? 0u : 0x80000000u;
}

// sample_light_among's counterpart through the tree: r_select below `bound` (the upper bound
// of the entries it may draw, light_bvh_bound() or less; at or above light_bvh_bound() it is
// the environment) chooses the light, whose probability is divided by `mass` as there.
bool sample_light_bvh(vec3 p, vec3 n, uint r_select, float mass, uint r_texel, vec2 u,
                      out LightSample s) {
    s.delta = false;
    s.radiance = vec3(0.0);
    s.pdf = 0.0;
    s.distance = 0.0;
    s.direction = vec3(0.0, 1.0, 0.0);
    s.entry = 0u;
    uint tree = light_bvh_bound();
    if (!(mass > 0.0)) return false;
    if (r_select >= tree) {
        // The environment's own range of the table (none: a scene without lights).
        if (scene.size.z == 0u || tree == 0x80000000u) return false;
        LightEntry e = light_entries[scene.size.z - 1u];
        bool found = sample_light_entry(e, e.probability / mass, p, r_texel, u, s);
        s.entry = scene.size.z - 1u;
        return found;
    }
    float share = float(tree) / 2147483648.0;
    float u_tree = min(float(r_select) / float(tree), ONE_MINUS_EPSILON);
    uint entry;
    float pmf;
    if (!light_bvh_select(p, n, u_tree, entry, pmf)) return false;
    bool found = sample_light_entry(light_entries[entry], pmf * share / mass, p, r_texel, u, s);
    s.entry = entry;
    return found;
}

// The selection probability of emissive GPU triangle `st` (the tree's pmf times its share of
// the table) for a path at (p, n), to be divided by the caller's mass.
float light_bvh_triangle_probability(ShadingTriangle st, vec3 p, vec3 n) {
    uint entry = floatBitsToUint(st.geometric_normal.w);
    if (entry >= scene.size.z) return 0.0;
    return light_bvh_pmf(p, n, entry) * (float(light_bvh_bound()) / 2147483648.0);
}

#endif
