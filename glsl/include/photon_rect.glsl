// A receiver rectangle RECT_i of Hu & Qin 2007 §2.2.1 (Fig. 12-13), as the photon-buffer
// caustics (§3, src/technique/caustics/photon_buffer.rs) use it.
#ifndef PRISM_PHOTON_RECT_GLSL
#define PRISM_PHOTON_RECT_GLSL
#include "prism_shared.glsl"

// Texture coordinates of x on RECT_i: "project P to caustic texture" (Fig. 23).
vec2 rect_uv(GpuPhotonRect r, vec3 x) {
    vec4 clip = r.view_proj * vec4(x, 1.0);
    return clip.xy / clip.w * 0.5 + 0.5;
}
#endif
