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
// A dielectric has no diffuse albedo: where Wyman 2005 shades it (WYMAN_DN), rg carry its d_N
// interpolated from the vertices (§3.1) as two halves, the value rounded and the remainder,
// whose sum is within 2^-22 of d_N (plus 2^-25 absolute where the remainder is subnormal):
// 22 of a float's 24 bits (glsl/refraction/wyman.glsl adds them); b = 0.
layout(location = 1) out vec4 out_albedo;
void main() {
    vec3 n = in_normal;
    float len = length(n);
    n = len > 1e-20 ? n / len : vec3(0.0, 1.0, 0.0);
    out_normal_material = vec4(n, float(pc.material));
    if (WYMAN_DN != 0u && material_kind(pc.material) == MATERIAL_DIELECTRIC) {
        // The larger half is exact in the target, so the rounding of the target's conversion
        // only touches the remainder. 65504: the largest half.
        float d = clamp(in_d_n, 0.0, 65504.0);
        float hi = unpackHalf2x16(packHalf2x16(vec2(d, 0.0))).x;
        out_albedo = vec4(hi, d - hi, 0.0, float(pc.object));
        return;
    }
    vec3 albedo = albedo_at(materials[pc.material], in_checker_uv);
    out_albedo = vec4(albedo, float(pc.object));
}
