#version 450
#include "prism_shared.glsl"
// Gaussian filter weight of a photon splat (Szirmay-Kalos et al. 2005, §5: "The filter
// texture corresponds to Gaussian filtering in texture space"), additively blended into the
// light map: irradiance in W/m^2 (the BRDF is applied when the light map is read).
layout(push_constant) uniform LightmapSplatPushBlock { LightmapSplatPush pc; };
layout(location = 0) flat in vec3 in_irradiance;
layout(location = 1) flat in vec2 in_center;
layout(location = 0) out vec4 out_irradiance;
void main() {
    vec2 d = gl_FragCoord.xy - in_center;
    float d2 = dot(d, d);
    float radius = pc.params.x;
    if (d2 > radius * radius) discard;
    float sigma = radius * 0.5;
    out_irradiance = vec4(in_irradiance * exp(-d2 / (2.0 * sigma * sigma)), 0.0);
}
