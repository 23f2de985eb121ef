#version 450
// G-buffer vertices: world space (objects are baked to world space at load time), plus, when
// a refractor is shaded by Wyman 2005, its per-vertex distance d_N along the inverted normal
// (§3.1), indexed by gl_VertexIndex (which includes the draw's vertex offset, so it indexes
// the scene-wide vertex array).
#include "frame.glsl"
layout(constant_id = 0) const uint WYMAN_DN = 0;
layout(set = 1, binding = BINDING_REFR_DN, std430) readonly buffer DistanceAlongNormal {
    float d_n[];
};
layout(location = 0) in vec3 in_position;
layout(location = 1) in vec3 in_normal;
layout(location = 2) in vec2 in_checker_uv;
layout(location = 0) out vec3 out_position;
layout(location = 1) out vec3 out_normal;
layout(location = 2) out vec2 out_checker_uv;
layout(location = 3) out float out_d_n;
void main() {
    out_position = in_position;
    out_normal = in_normal;
    out_checker_uv = in_checker_uv;
    out_d_n = WYMAN_DN != 0u ? d_n[gl_VertexIndex] : 0.0;
    gl_Position = frame.view_proj * vec4(in_position, 1.0);
}
