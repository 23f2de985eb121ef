// A receiver rectangle RECT_i of Hu & Qin 2007 §2.2.1 (Fig. 12-13), as the photon-buffer
// caustics (§3, src/technique/caustics/photon_buffer.rs) use it. Mirrors GpuPhotonRect (std430).
#ifndef PRISM_PHOTON_RECT_GLSL
#define PRISM_PHOTON_RECT_GLSL
struct PhotonRect {
    mat4 view_proj;   // world -> RECT_i's parallel projection from O_R along O_R O_i (glOrtho(-d, d, -d, d))
    vec4 axis;        // xyz: unit O_R -> O_i, the rectangle's normal; w: d_i (half the side)
    vec4 centre;      // xyz: O_i; w: radius of the receiver object around O_i (m)
    uvec4 object;     // x: the receiver's object index (the G-buffer's albedo.a)
};

// Texture coordinates of x on RECT_i: "project P to caustic texture" (Fig. 23).
vec2 rect_uv(PhotonRect r, vec3 x) {
    vec4 clip = r.view_proj * vec4(x, 1.0);
    return clip.xy / clip.w * 0.5 + 0.5;
}
#endif
