#version 450
// PNG output rule of SCENES.md: srgb_oetf(clamp(exposure * L, 0, 1)).
#include "frame.glsl"
#include "color.glsl"
layout(set = 1, binding = BINDING_HDR) uniform sampler2D hdr;
layout(location = 0) in vec2 in_uv;
layout(location = 0) out vec4 out_color;
void main() {
    vec3 L = finite_or_zero(texelFetch(hdr, ivec2(gl_FragCoord.xy), 0).rgb);
    out_color = vec4(srgb_oetf(frame.camera_position.w * L), 1.0);
}
