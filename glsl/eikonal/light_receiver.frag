#version 450
// Diffuse receivers of the G-buffer inside the irradiance volume receive the simulated light
// (Ihrke et al. 2007, Fig. 1 left: the caustic on the table): glsl/eikonal/receiver.glsl.
#include "frame.glsl"
#include "environment.glsl"
#include "lighting.glsl"
layout(set = 1, binding = BINDING_GBUF_NORMAL) uniform sampler2D gbuf_normal;
layout(set = 1, binding = BINDING_GBUF_ALBEDO) uniform sampler2D gbuf_albedo;
layout(set = 1, binding = BINDING_GBUF_DEPTH) uniform sampler2D gbuf_depth;
#include "scatter.glsl"
layout(constant_id = 0) const float LIGHT_MIN_X = 0.0;
layout(constant_id = 1) const float LIGHT_MIN_Y = 0.0;
layout(constant_id = 2) const float LIGHT_MIN_Z = 0.0;
layout(constant_id = 3) const float LIGHT_MAX_X = 1.0;
layout(constant_id = 4) const float LIGHT_MAX_Y = 1.0;
layout(constant_id = 5) const float LIGHT_MAX_Z = 1.0;
#include "receiver.glsl"
layout(location = 0) in vec2 in_uv;
layout(location = 0) out vec4 out_radiance;

void main() {
    ivec2 px = ivec2(gl_FragCoord.xy);
    float depth = texelFetch(gbuf_depth, px, 0).r;
    if (depth <= 0.0) discard;
    vec4 nm = texelFetch(gbuf_normal, px, 0);
    if (material_kind(uint(nm.w + 0.5)) != MATERIAL_DIFFUSE) discard;
    vec3 p = world_from_depth(in_uv, depth);
    vec3 lo = vec3(LIGHT_MIN_X, LIGHT_MIN_Y, LIGHT_MIN_Z), hi = vec3(LIGHT_MAX_X, LIGHT_MAX_Y, LIGHT_MAX_Z);
    if (!eikonal_receives(p, lo, hi)) discard;
    vec3 n = normalize(nm.xyz);
    if (dot(n, camera_ray(in_uv)) > 0.0) n = -n;
    vec3 albedo = texelFetch(gbuf_albedo, px, 0).rgb;
    out_radiance = vec4(eikonal_receiver(p, n, albedo, lo, hi), 1.0);
}
