#version 450
// TEX_i of Hu & Qin 2007 §2.2.1 (Fig. 13, "Rendering Pass"): OBJ_i's world-space vertices
// through the parallel projection from O_R towards O_i.
#include "push.glsl"
layout(location = 0) in vec3 in_position;
layout(location = 1) in vec3 in_normal;
layout(location = 2) in vec2 in_checker_uv;
layout(location = 0) out vec3 out_position;
layout(location = 1) out vec3 out_normal;
layout(location = 2) out vec2 out_checker_uv;
void main() {
    out_position = in_position;
    out_normal = in_normal;
    out_checker_uv = in_checker_uv;
    gl_Position = pc.view_proj * vec4(in_position, 1.0);
}
