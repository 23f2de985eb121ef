#version 450
// Light-map caustics (Szirmay-Kalos et al. 2005, §5): the specular objects seen from the light.
#include "lightmap_push.glsl"
layout(location = 0) in vec3 in_position;
layout(location = 1) in vec3 in_normal;
layout(location = 2) in vec2 in_checker_uv;
layout(location = 0) out vec3 out_position;
layout(location = 1) out vec3 out_normal;
void main() {
    out_position = in_position;
    out_normal = in_normal;
    gl_Position = pc.view_proj * vec4(in_position, 1.0);
}
