#version 450
// G-buffer: every visible surface's normal, material and diffuse albedo (MRT).
#include "frame.glsl"
layout(constant_id = 0) const uint WYMAN_DN = 0;
layout(push_constant) uniform GbufferPushBlock { GbufferPush pc; };
layout(location = 0) in vec3 in_position;
layout(location = 1) in vec3 in_normal;
layout(location = 2) in vec2 in_checker_uv;
layout(location = 3) in float in_d_n;
// RT0 (RGBA16F): xyz = unit world normal as interpolated (not flipped to the viewer), w = material index.
layout(location = 0) out vec4 out_normal_material;
// RT1 (RGBA16F): rgb = diffuse albedo with the checker evaluated, a = object index (exact in
// half float up to 2048: per-object distance impostors and light maps pick their pixels by it).
// A dielectric has no diffuse albedo: where Wyman 2005 shades it (WYMAN_DN), rgb carry its
// d_N interpolated from the vertices (§3.1), the float's 32 bits as three whole numbers of
// 11, 11 and 10 bits, each exact in a half (glsl/refraction/wyman.glsl puts them together):
// the very float a 32-bit target would hold, at any scene scale.
layout(location = 1) out vec4 out_albedo;
void main() {
    vec3 n = in_normal;
    float len = length(n);
    n = len > 1e-20 ? n / len : vec3(0.0, 1.0, 0.0);
    out_normal_material = vec4(n, float(pc.material));
    if (WYMAN_DN != 0u && material_kind(pc.material) == MATERIAL_DIELECTRIC) {
        uint bits = floatBitsToUint(max(in_d_n, 0.0));
        out_albedo = vec4(float(bits & 0x7ffu), float((bits >> 11) & 0x7ffu), float(bits >> 22), float(pc.object));
        return;
    }
    vec3 albedo = albedo_at(materials[pc.material], in_checker_uv);
    out_albedo = vec4(albedo, float(pc.object));
}
