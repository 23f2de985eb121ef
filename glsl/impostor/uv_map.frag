#version 450
// The uv map of light-map caustics (Szirmay-Kalos et al. 2005, §5): "together with the
// environment map, we also render another map, called uvmap, which has the same structure,
// but stores the u, v coordinates and the texture id in its pixels". Here: the visible
// receiver's light-map (u, v) and slot + 1, and (for Hit(), §3) the distance of the visible
// surface from the reference point, per pixel, in the same cube.
// Surfaces without a light map store id 0: photons that hit them are dropped.
#include "map_push.glsl"
layout(location = 0) in vec3 in_position;
layout(location = 1) in vec3 in_normal;
layout(location = 2) in vec2 in_checker_uv;
// RT0 (RGBA32F): r, g = light-map (u, v); b = light-map slot + 1 (0: none); a = |p - o|.
layout(location = 0) out vec4 out_uv_id_distance;
void main() {
    float dist = length(in_position - pc.reference.xyz);
    vec2 uv = vec2(dot(pc.chart_u.xyz, in_position) + pc.chart_u.w, dot(pc.chart_v.xyz, in_position) + pc.chart_v.w);
    out_uv_id_distance = vec4(pc.material.y > 0u ? uv : vec2(0.0), float(pc.material.y), dist);
}
