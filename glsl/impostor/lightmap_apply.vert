#version 450
// The pixels where one receiver chart can be seen, for the apply pass (Szirmay-Kalos et al.
// 2005 §5: each receiver adds its light map during deferred shading): the chart's own
// rectangle, origin + a edge_u + b edge_v, drawn in the scene instead of a full-screen
// triangle, so that a scene of many charts (a room's walls and boxes, one chart per face) does
// not shade the whole image once per chart. The rectangle is the receiver face itself (a quad
// or a box face, src/technique/impostor/impostor_lightmap.rs `Chart`), widened by 1% of each
// edge so that every pixel the fragment shader keeps (uv within 1e-3 of the chart) is inside
// it; where it crosses the camera's plane the rasterizer clips it. Both sides are drawn.
// Of the rectangle only the part the photons can reach is drawn (the texels their splats
// and bilinear lookups touch, found while rendering the caustic maps: lightmap_caustic.frag),
// since the light map is exactly 0 elsewhere: the same image for a fraction of the pixels
// where a caustic covers a fraction of its receiver. A light map no photon reached draws nothing.
#include "frame.glsl"
layout(constant_id = 1) const uint LIGHTMAP_SIZE = 256;
layout(push_constant) uniform LightmapApplyPushBlock { LightmapApplyPush pc; };
layout(set = 1, binding = BINDING_LIGHTMAP_REACH, std430) readonly buffer Reach { uint reach[]; };
const vec2 CORNERS[6] = vec2[6](vec2(0.0, 0.0), vec2(1.0, 0.0), vec2(1.0, 1.0),
                                vec2(0.0, 0.0), vec2(1.0, 1.0), vec2(0.0, 1.0));
void main() {
    uint s = 4u * uint(pc.origin.w + 0.5);
    uvec2 lo = uvec2(reach[s], reach[s + 1u]);
    uvec2 hi = uvec2(0xFFFFFFFFu) - uvec2(reach[s + 2u], reach[s + 3u]);
    if (any(greaterThan(lo, hi))) {
        gl_Position = vec4(2.0, 2.0, 2.0, 1.0);   // outside the clip volume: nothing drawn
        return;
    }
    // Texel k spans [k, k + 1] / size; at the light map's edges the rectangle's 1% margin.
    float n = float(LIGHTMAP_SIZE);
    vec2 a = mix(vec2(lo) / n, vec2(-0.01), equal(lo, uvec2(0u)));
    vec2 b = mix(vec2(hi + 1u) / n, vec2(1.01), equal(hi, uvec2(LIGHTMAP_SIZE - 1u)));
    vec2 c = mix(a, b, CORNERS[gl_VertexIndex]);
    vec3 p = pc.origin.xyz + c.x * pc.edge_u.xyz + c.y * pc.edge_v.xyz;
    gl_Position = frame.view_proj * vec4(p, 1.0);
}
