#version 450
// The `lightfield` method's step 1 (Lu 14 Section 4.5.1): per G-buffer point p of one placed
// luminaire, A(p) = sum over the images of A_m(p), each image's share of the samples
// (luminaire.glsl's image_share: the window's integral from the summed-area table, Eq. 4.14),
// written to LuminaireAreas for shade_lightfield.comp's split (Eq. 4.16). 0 where the point
// gets none of the luminaire's light: not a surface, at or behind the image plane, or every
// window dark.

#extension GL_GOOGLE_include_directive : require

layout(local_size_x = 8, local_size_y = 8, local_size_z = 1) in;

#include "scene.glsl"
#include "gbuffer.glsl"
#include "luminaire.glsl"

layout(set = 0, binding = 36, std430) writeonly buffer LuminaireAreas { float luminaire_areas[]; };

void main() {
    uvec2 pixel = gl_GlobalInvocationID.xy;
    if (pixel.x >= scene.size.x || pixel.y >= scene.size.y) return;
    uint index = pixel.y * scene.size.x + pixel.x;
    GBufferTexel g = gbuffer[index];
    vec3 wo, side, n;
    float total = 0.0;
    if (gbuffer_surface(g, wo, side, n)) {
        vec3 p = to_luminaire(g.position.xyz);
        if (p.z > lf.plane.z) {
            bool near = uses_filter_plane(p);
            for (uint m = 0u; m < luminaire_images(); ++m) total += image_share(m, p, near);
        }
    }
    luminaire_areas[index] = total;
}
