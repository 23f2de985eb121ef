#version 450
// The uv cube map of light-map caustics (Szirmay-Kalos et al. 2005, §5, Fig. 9): "a uv
// cube map ... rendered with the environment distance impostor from the same reference
// point", storing per texel the visible receiver's light-map (u, v) and texture id, and (for
// Hit(), §3) the distance of the visible surface from the reference point, per pixel.
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
