#version 450
// A dielectric OBJ_k's nearest back faces (FRONT 0) or front faces (FRONT 1) in its
// rectangle's parallel projection (Hu & Qin 2007 §2.1's "initial pass", here in the impostor
// texture's view for §2.2.1's recursive refraction): the layers on which the exit search in
// glsl/nearby/impostor_body.glsl (glsl/include/hu_qin_exit.glsl: Figs. 5, 7, 9) finds the exit
// point P2, and its normal N2 (§2.1.4). The other faces are culled by the pipeline.
#include "push.glsl"
layout(constant_id = 0) const uint FRONT = 0;
layout(location = 0) in vec3 in_position;
layout(location = 1) in vec3 in_normal;
layout(location = 2) in vec2 in_checker_uv;
// RT0 (RGBA32F): xyz = unit outward normal (zero where no surface: the coverage test),
// w = axial distance dot(p - O_R, n_i), the same depth as TEX_DEPTH_i.
layout(location = 0) out vec4 out_back;
void main() {
    vec3 n = in_normal;
    float len = length(n);
    n = len > 1e-20 ? n / len : (FRONT != 0u ? -pc.axis.xyz : pc.axis.xyz);
    // A back face seen along the projection faces away from it, a front face towards it.
    if (FRONT != 0u ? dot(n, pc.axis.xyz) > 0.0 : dot(n, pc.axis.xyz) < 0.0) n = -n;
    out_back = vec4(n, dot(in_position - pc.origin.xyz, pc.axis.xyz));
}
