#version 450
// Lu 14 Section 3.3.3 and Alg. 1 line 6: the cube map that drives environment sampling, rebuilt
// from the scene's equirectangular map every frame. Each cube texel's weight is its luminance
// times its solid angle, the luminance being the largest over the map texels its footprint
// touches (a conservative maximum: the cube map only shapes the pdf, so it must be positive
// wherever the map is, and point sampling would lose a sun smaller than a cube texel). The
// footprint: the texel's corners and the edge points where the polar angle can peak (4 to 8)
// mapped to the map's rows and columns, the columns unwrapped across the seam, one map texel of
// margin on every side, and every column with the rows up to the pole for the texel that holds
// a pole. One invocation
// per cube texel: (i, j, face). src/sampling/cubemap.rs mirrors it (cube_weights).
//
// The footprint's texels, taken row by row, are split over dispatches: each takes the range
// [first, first + count) of them and keeps the larger of its peak and the weight an earlier
// dispatch wrote (first 0 writes). A texel near a pole covers the map's whole width, so its
// footprint grows as w h / R; src/methods/envmap/cube.rs bounds it (footprint_bound) and records
// as many dispatches as the bound needs, so lavapipe's loop budget never cuts the search.

#extension GL_GOOGLE_include_directive : require

layout(local_size_x = 8, local_size_y = 8, local_size_z = 1) in;

// bvh.glsl only because the scene bindings come as one set (GpuScene::bindings).
#include "bvh.glsl"
#include "scene.glsl"
#include "sampling.glsl"
#include "cubemap.glsl"

layout(set = 0, binding = 20, std430) buffer CubeWeights { float cube_weights[]; };

layout(push_constant) uniform CubeParams {
    uint resolution;  // R: texels along a face's side
    uint first;       // the first footprint texel this dispatch takes, row-major
    uint count;       // how many it takes at most
    uint planned;     // how many the dispatches take in all (footprint_bound, rounded up)
} params;

// The continuous (column, row) of direction d on the W x H map.
vec2 map_coordinates(vec3 d) {
    float u = fract(atan(d.x, -d.z) * (0.5 * INV_PI));
    float v = acos(clamp(d.y, -1.0, 1.0)) * INV_PI;
    return vec2(u * float(scene.env_size.x), v * float(scene.env_size.y));
}

void main() {
    uint r = params.resolution;
    uint i = gl_GlobalInvocationID.x;
    uint j = gl_GlobalInvocationID.y;
    uint f = gl_GlobalInvocationID.z;
    if (i >= r || j >= r || f >= 6u) return;
    int w = int(scene.env_size.x);
    int h = int(scene.env_size.y);
    float s = 2.0 / float(r);
    vec2 lo = vec2(-1.0 + s * float(i), -1.0 + s * float(j));
    vec2 hi = lo + s;

    // The walk: each corner counter-clockwise (bottom-left, bottom-right, top-right, top-left),
    // and after it, where the edge it starts crosses the line on which the polar angle along
    // the edge can peak (u = 0 on edges of constant v; v = 0 on edges of constant u, on +Y and
    // -Y only), the crossing. The azimuth's extremes are at corners, the polar angle's at
    // corners or crossings (src/sampling/cubemap.rs `equirect_footprint` has the argument).
    bool polar_face = f == 2u || f == 3u;
    bool crosses_u = lo.x < 0.0 && hi.x > 0.0;
    bool crosses_v = polar_face && lo.y < 0.0 && hi.y > 0.0;
    vec2 walk[8];
    uint count = 0u;
    walk[count++] = lo;
    if (crosses_u) walk[count++] = vec2(0.0, lo.y);
    walk[count++] = vec2(hi.x, lo.y);
    if (crosses_v) walk[count++] = vec2(hi.x, 0.0);
    walk[count++] = hi;
    if (crosses_u) walk[count++] = vec2(0.0, hi.y);
    walk[count++] = vec2(lo.x, hi.y);
    if (crosses_v) walk[count++] = vec2(lo.x, 0.0);

    float row_min = 1e30;
    float row_max = -1e30;
    float col_previous = 0.0;
    float col_min = 1e30;
    float col_max = -1e30;
    for (uint k = 0u; k < count; ++k) {
        vec2 uv = walk[k];
        vec2 c = map_coordinates(normalize(cube_face_point(f, uv.x, uv.y)));
        row_min = min(row_min, c.y);
        row_max = max(row_max, c.y);
        float col = c.x;
        if (k > 0u) {
            float step = col - mod(col_previous, float(w));
            if (step > 0.5 * float(w)) step -= float(w);
            if (step <= -0.5 * float(w)) step += float(w);
            col = col_previous + step;
        }
        col_previous = col;
        col_min = min(col_min, col);
        col_max = max(col_max, col);
    }
    int j0 = max(int(floor(row_min)) - 1, 0);
    int j1 = min(int(floor(row_max)) + 1, h - 1);
    int i0 = int(floor(col_min)) - 1;
    int i1 = int(floor(col_max)) + 1;
    bool pole = (f == 2u || f == 3u) && lo.x <= 0.0 && hi.x >= 0.0 && lo.y <= 0.0 && hi.y >= 0.0;
    if (pole) {
        if (f == 2u) j0 = 0; else j1 = h - 1;
    }
    if (pole || i1 - i0 + 1 >= w) {
        i0 = 0;
        i1 = w - 1;
    }

    uint columns = uint(i1 - i0 + 1);
    uint texels = uint(j1 - j0 + 1) * columns;
    // The bound is proven (footprint_bound); should a footprint ever pass it, the render is
    // refused rather than the texels past it left out.
    if (params.first == 0u && texels > params.planned) loop_cuts = 1u;
    if (params.first >= texels) return;
    uint end = min(texels, params.first + params.count);
    int row = j0 + int(params.first / columns);
    int col = i0 + int(params.first % columns);
    float peak = 0.0;
    for (uint k = params.first; k < end; ++k) {
        int wrapped = ((col % w) + w) % w;
        peak = max(peak, luminance(env_texels[row * w + wrapped].rgb));
        if (++col > i1) {
            col = i0;
            ++row;
        }
    }
    uint index = (f * r + j) * r + i;
    float weight = peak * cube_texel_solid_angle(r, i, j);
    cube_weights[index] = params.first == 0u ? weight : max(cube_weights[index], weight);
}
