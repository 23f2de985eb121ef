#version 450
// Caustics mapping (Shah et al. 2007, §III.B step 2): the specular objects seen from the
// light, one source face of the vertex grid at a time, with Wyman 2005's per-vertex d_N
// (§3.1) for the exit estimate of double-surface refraction. gl_VertexIndex includes the
// draw's vertex offset, so it indexes the scene-wide vertex array.
#include "prism_shared.glsl"
layout(push_constant) uniform RefractorPushBlock { RefractorPush pc; };
layout(set = 0, binding = CAUSTIC_BINDING_DN, std430) readonly buffer DistanceAlongNormal { float d_n[]; };
layout(location = 0) in vec3 in_position;
layout(location = 1) in vec3 in_normal;
layout(location = 2) in vec2 in_checker_uv;
layout(location = 0) out vec3 out_position;
layout(location = 1) out vec3 out_normal;
layout(location = 2) out float out_d_n;
void main() {
    out_position = in_position;
    out_d_n = d_n[gl_VertexIndex];
    out_normal = in_normal;
    gl_Position = pc.view_proj * vec4(in_position, 1.0);
}
