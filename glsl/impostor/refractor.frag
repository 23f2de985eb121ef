#version 450
// The refractor map (Szirmay-Kalos et al. 2005, §4): "a distance impostor for each
// refractor, which stores the distance of the refractor surface from its center and the
// normal vector of the surface". Only the refractor is drawn; from its centre every point of
// a not strongly concave refractor is visible.
#include "frame.glsl"
#include "map_push.glsl"
layout(location = 0) in vec3 in_position;
layout(location = 1) in vec3 in_normal;
layout(location = 2) in vec2 in_checker_uv;
// RT0 (RGBA32F): xyz = unit outward normal as interpolated; w = |p - centre|.
layout(location = 0) out vec4 out_normal_distance;
void main() {
    vec3 n = in_normal;
    float len = length(n);
    vec3 to_p = in_position - pc.reference.xyz;
    n = len > 1e-20 ? n / len : normalize(to_p);
    out_normal_distance = vec4(n, length(to_p));
}
