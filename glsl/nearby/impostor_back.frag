#version 450
// A dielectric OBJ_k's nearest back faces in its rectangle's parallel projection (Hu & Qin
// 2007 §2.1's "initial pass", here in the impostor texture's view for §2.2.1's recursive
// refraction): the surface the Fig. 9 search in glsl/nearby/impostor_body.glsl finds the
// exit point P2 on, and its normal N2 (§2.1.4). Front faces are culled by the pipeline.
#include "push.glsl"
layout(location = 0) in vec3 in_position;
layout(location = 1) in vec3 in_normal;
layout(location = 2) in vec2 in_checker_uv;
// RT0 (RGBA32F): xyz = unit outward normal (zero where no surface: the coverage test),
// w = axial distance dot(p - O_R, n_i), the same depth as TEX_DEPTH_i.
layout(location = 0) out vec4 out_back;
void main() {
    vec3 n = in_normal;
    float len = length(n);
    n = len > 1e-20 ? n / len : pc.axis.xyz;
    // A back face seen along the projection faces away from it.
    if (dot(n, pc.axis.xyz) < 0.0) n = -n;
    out_back = vec4(n, dot(in_position - pc.origin.xyz, pc.axis.xyz));
}
