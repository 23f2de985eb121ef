#version 450
// Refractor layers (src/technique/refraction/refractor_layers.rs): world-space vertices.
#include "frame.glsl"
layout(location = 0) in vec3 in_position;
layout(location = 1) in vec3 in_normal;
layout(location = 2) in vec2 in_checker_uv;
layout(location = 0) out vec3 out_normal;
void main() {
    out_normal = in_normal;
    gl_Position = frame.view_proj * vec4(in_position, 1.0);
}
