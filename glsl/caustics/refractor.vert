#version 450
// Caustics mapping (Shah et al. 2007, §III.B step 2): the specular objects seen from the
// light, one source face of the vertex grid at a time.
#include "prism_shared.glsl"
layout(push_constant) uniform RefractorPushBlock { RefractorPush pc; };
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
