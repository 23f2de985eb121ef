#version 450
#include "prism_shared.glsl"
// Light-space vertex transform for one shadow-map face.
layout(push_constant) uniform ShadowPushBlock { ShadowPush pc; };
layout(location = 0) in vec3 in_position;
layout(location = 1) in vec3 in_normal;
layout(location = 2) in vec2 in_checker_uv;
layout(location = 0) out vec3 out_position;
void main() {
    out_position = in_position;
    gl_Position = pc.view_proj * vec4(in_position, 1.0);
}
