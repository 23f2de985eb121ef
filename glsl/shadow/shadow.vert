#version 450
// Light-space vertex transform for one shadow-map face.
layout(push_constant) uniform Push {
    mat4 view_proj;   // world -> face clip space
    vec4 light;       // xyz: position (point) or direction (directional); w: kind
    vec4 origin;      // directional: origin of the distance plane
} pc;
layout(location = 0) in vec3 in_position;
layout(location = 1) in vec3 in_normal;
layout(location = 2) in vec2 in_checker_uv;
layout(location = 0) out vec3 out_position;
void main() {
    out_position = in_position;
    gl_Position = pc.view_proj * vec4(in_position, 1.0);
}
