#version 450
// The specular surfaces nearest the light, for the caustic map of light-map caustics
// (Szirmay-Kalos et al. 2005, §5; lightmap_caustic.frag shades them afterwards, one texel
// at a time): RT0 xyz world position, w material index + 1 (cleared to 0: no surface);
// RT1 xyz the interpolated normal as the rasterizer gives it (not renormalised).
#include "lightmap_push.glsl"
layout(location = 0) in vec3 in_position;
layout(location = 1) in vec3 in_normal;
layout(location = 0) out vec4 out_position;
layout(location = 1) out vec4 out_normal;
void main() {
    out_position = vec4(in_position, pc.intensity.w + 1.0);
    out_normal = vec4(in_normal, 0.0);
}
