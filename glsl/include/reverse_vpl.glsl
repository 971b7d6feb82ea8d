// bir's reverse VPLs (Segovia 06 Section 3.1), laid out as VPLs (vpl.glsl): kind VPL_AREA, a
// diffuse emitter at x2 on the side its camera path arrived from; normal.w its material;
// power.rgb pi L_o weight / (R p(x2)) once shade_reverse_vpls.comp has run, power.w the
// density p(x2) (area measure); incident.xyz the geometric normal on the emitting side, w its
// GPU triangle (uint bits; texture.glsl's lookup needs it).
// Binding 16.
#ifndef REVERSE_VPL_GLSL
#define REVERSE_VPL_GLSL

#ifdef REVERSE_VPL_WRITE
layout(set = 0, binding = 16, std430) buffer ReverseVpls { Vpl reverse_vpls[]; };
#else
layout(set = 0, binding = 16, std430) readonly buffer ReverseVpls { Vpl reverse_vpls[]; };
#endif

#endif
