#version 450
// Stores the distance from the light (point) or from the light's plane along its direction
// (directional). Comparing distances instead of projected depth lets one lookup rule serve
// the six faces of a cube and the orthographic map alike.
#include "prism_shared.glsl"
layout(push_constant) uniform ShadowPushBlock { ShadowPush pc; };
layout(location = 0) in vec3 in_position;
layout(location = 0) out float out_distance;
void main() {
    if (uint(pc.light.w + 0.5) == LIGHT_POINT) {
        out_distance = length(in_position - pc.light.xyz);
    } else {
        out_distance = dot(in_position - pc.origin.xyz, pc.light.xyz);
    }
}
