#version 450
#include "prism_shared.glsl"
// The Gaussian weights of the (up to) four photons of a block sprite
// (lightmap_splat_block.vert), each as lightmap_splat.frag weighs one, summed and additively
// blended into the light map.
layout(push_constant) uniform LightmapSplatPushBlock { LightmapSplatPush pc; };
layout(location = 0) flat in vec4 in_irradiance[4];
layout(location = 4) flat in vec4 in_centers[2];
layout(location = 0) out vec4 out_irradiance;
void main() {
    float radius = pc.params.x;
    float sigma = radius * 0.5;
    vec3 sum = vec3(0.0);
    bool any_texel = false;
    for (int i = 0; i < 4; ++i) {
        vec2 c = (i & 1) == 0 ? in_centers[i >> 1].xy : in_centers[i >> 1].zw;
        vec2 d = gl_FragCoord.xy - c;
        float d2 = dot(d, d);
        if (in_irradiance[i].a > 0.0 && d2 <= radius * radius) {
            sum += in_irradiance[i].rgb * exp(-d2 / (2.0 * sigma * sigma));
            any_texel = true;
        }
    }
    if (!any_texel) discard;
    out_irradiance = vec4(sum, 0.0);
}
