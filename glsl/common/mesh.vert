#version 450
// World-space mesh vertices (objects are baked to world space at load time).
#include "frame.glsl"
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
    gl_Position = frame.view_proj * vec4(in_position, 1.0);
}
