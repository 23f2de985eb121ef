#version 450
// G-buffer: every visible surface's normal, material and diffuse albedo (MRT).
#include "frame.glsl"
layout(push_constant) uniform GbufferPushBlock { GbufferPush pc; };
layout(location = 0) in vec3 in_position;
layout(location = 1) in vec3 in_normal;
layout(location = 2) in vec2 in_checker_uv;
// RT0 (RGBA16F): xyz = unit world normal as interpolated (not flipped to the viewer), w = material index.
layout(location = 0) out vec4 out_normal_material;
// RT1 (RGBA16F): rgb = diffuse albedo with the checker evaluated, a = object index (exact in
// half float up to 2048: per-object distance impostors and light maps pick their pixels by it).
layout(location = 1) out vec4 out_albedo;
void main() {
    vec3 n = in_normal;
    float len = length(n);
    n = len > 1e-20 ? n / len : vec3(0.0, 1.0, 0.0);
    vec3 albedo = albedo_at(materials[pc.material], in_checker_uv);
    out_normal_material = vec4(n, float(pc.material));
    out_albedo = vec4(albedo, float(pc.object));
}
