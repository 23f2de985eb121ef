#version 450
// The pixels where one receiver chart can be seen, for the apply pass (Szirmay-Kalos et al.
// 2005 §5: each receiver adds its light map during deferred shading): the chart's own
// rectangle, origin + a edge_u + b edge_v, drawn in the scene instead of a full-screen
// triangle, so that a scene of many charts (a room's walls and boxes, one chart per face) does
// not shade the whole image once per chart. The rectangle is the receiver face itself (a quad
// or a box face, src/technique/impostor/impostor_lightmap.rs `Chart`), widened by 1% of each
// edge so that every pixel the fragment shader keeps (uv within 1e-3 of the chart) is inside
// it; where it crosses the camera's plane the rasterizer clips it. Both sides are drawn.
#include "frame.glsl"
layout(push_constant) uniform LightmapApplyPushBlock { LightmapApplyPush pc; };
const vec2 CORNERS[6] = vec2[6](vec2(0.0, 0.0), vec2(1.0, 0.0), vec2(1.0, 1.0),
                                vec2(0.0, 0.0), vec2(1.0, 1.0), vec2(0.0, 1.0));
void main() {
    vec2 c = mix(vec2(-0.01), vec2(1.01), CORNERS[gl_VertexIndex]);
    vec3 p = pc.origin.xyz + c.x * pc.edge_u.xyz + c.y * pc.edge_v.xyz;
    gl_Position = frame.view_proj * vec4(p, 1.0);
}
