// The environment distance impostor (Szirmay-Kalos et al. 2005, §2 and §3): radiance of the
// visible surface as the camera would see it (the deferred result: glsl/include/lighting.glsl)
// and its distance from the reference point, computed here per pixel because "the distance
// is a non linear function of the homogeneous coordinates" (§3): interpolating it per vertex
// would bend planar walls. IMPOSTOR_SEPARATE selects where the distance goes: the alpha
// channel (0) or a separate R32F target (1, §6).
#include "frame.glsl"
#include "lighting.glsl"
#include "map_push.glsl"
layout(location = 0) in vec3 in_position;
layout(location = 1) in vec3 in_normal;
layout(location = 2) in vec2 in_checker_uv;
// RT0 (RGBA32F): rgb = outgoing radiance towards o; a = |p - o| (or 0 with a separate distance).
layout(location = 0) out vec4 out_radiance;
#if IMPOSTOR_SEPARATE
// RT1 (R32F): |p - o|.
layout(location = 1) out float out_distance;
#endif
void main() {
    vec3 to_p = in_position - pc.reference.xyz;
    float dist = length(to_p);
    uint mat = pc.material.x;
    vec3 radiance = vec3(0.0);
    // Specular surfaces other than the map's own object are black, as in deferred shading
    // before their technique's pass: the map holds what the diffuse pass computes.
    if (material_kind(mat) == MATERIAL_DIFFUSE) {
        vec3 n = in_normal;
        float len = length(n);
        n = len > 1e-20 ? n / len : vec3(0.0, 1.0, 0.0);
        // Two-sided diffuse: shade the side the reference point sees.
        if (dot(n, to_p) > 0.0) n = -n;
        radiance = diffuse_radiance(in_position, n, albedo_at(materials[mat], in_checker_uv));
    }
#if IMPOSTOR_SEPARATE
    out_radiance = vec4(radiance, 0.0);
    out_distance = dist;
#else
    out_radiance = vec4(radiance, dist);
#endif
}
