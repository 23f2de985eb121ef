#version 450
// The adaptive tone map (render.tonemap = "adaptive"): Reinhard et al. 2002's operator with
// the state adapt.comp derived this frame (Krawczyk et al. 2005's key and temporal
// adaptation), then the sRGB OETF of SCENES.md's PNG rule.
#include "color.glsl"
#include "adaptive.glsl"
layout(set = 1, binding = BINDING_HDR) uniform sampler2D hdr;
layout(set = 1, binding = BINDING_TONEMAP_STATE) uniform sampler2D state;
layout(location = 0) in vec2 in_uv;
layout(location = 0) out vec4 out_color;
void main() {
    vec3 c = tonemap_input(texelFetch(hdr, ivec2(gl_FragCoord.xy), 0).rgb);
    vec4 s = texelFetch(state, ivec2(0, 0), 0);
    out_color = vec4(srgb_oetf(tonemap_reinhard(c, s.x, s.y)), 1.0);
}
