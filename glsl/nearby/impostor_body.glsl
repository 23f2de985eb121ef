// TEX_i / TEX_DEPTH_i of Hu & Qin 2007 §2.2.1 (Fig. 13): the object's radiance as the
// camera would see it (direct light with shadow maps + environment irradiance, the same
// function as deferred shading: glsl/include/lighting.glsl), and the depth that the
// iterative lookup of Fig. 16 compares against, as the axial distance from O_R along the
// projection direction (linear in the ortho z, in world units).
// A mirror or conductor OBJ_k (§2.2.1's recursive reflections) reflects the parallel
// projection's view direction: at recursion level 0 it sees the environment
// only (impostor.frag); at level >= 1 (impostor_recursive.frag) it sees the other impostors
// of the level below. Included by both with NEARBY_RECURSIVE 0 or 1.
#include "frame.glsl"
#include "lighting.glsl"
#include "fresnel.glsl"
#include "push.glsl"
// Branch `eikview`: glsl/eikonal/nearby_impostor.frag shades diffuse objects with the
// eikonal light simulation's irradiance (eikonal_receiver, declared before this include).
#ifndef NEARBY_EIKONAL_LIGHT
#define NEARBY_EIKONAL_LIGHT 0
#endif
#if NEARBY_RECURSIVE
// The lookup of the level below: the same correction as refraction_hu_qin (constants 0..2).
layout(constant_id = 0) const uint NEARBY_ITERATIONS = 3;
layout(constant_id = 1) const float NEARBY_TOLERANCE = 1e-3;
layout(constant_id = 2) const uint NEARBY_SEEDS = 8;
#include "nearby.glsl"
#endif
layout(location = 0) in vec3 in_position;
layout(location = 1) in vec3 in_normal;
layout(location = 2) in vec2 in_checker_uv;
// RT0 (RGBA32F): rgb = outgoing radiance (HDR) towards O_R; a = dot(p - O_R, n_i).
layout(location = 0) out vec4 out_texel;
void main() {
    uint mat = pc.material.x;
    uint kind = material_kind(mat);
    vec3 n = in_normal;
    float len = length(n);
    n = len > 1e-20 ? n / len : -pc.axis.xyz;
    // Two-sided: shade the side the projection sees (it looks along +axis).
    if (dot(n, pc.axis.xyz) > 0.0) n = -n;
    vec3 radiance = vec3(0.0);
    if (kind == MATERIAL_DIFFUSE) {
#if NEARBY_EIKONAL_LIGHT
        vec3 lo = vec3(LIGHT_MIN_X, LIGHT_MIN_Y, LIGHT_MIN_Z), hi = vec3(LIGHT_MAX_X, LIGHT_MAX_Y, LIGHT_MAX_Z);
        radiance = eikonal_receiver(in_position, n, albedo_at(materials[mat], in_checker_uv), lo, hi);
#else
        radiance = diffuse_radiance(in_position, n, albedo_at(materials[mat], in_checker_uv));
#endif
    } else if (kind == MATERIAL_MIRROR || kind == MATERIAL_CONDUCTOR) {
        // The parallel projection's eye ray is +axis everywhere.
        vec3 R = reflect(pc.axis.xyz, n);
        float cos_i = clamp(-dot(pc.axis.xyz, n), 0.0, 1.0);
        Material m = materials[mat];
        vec3 F = kind == MATERIAL_MIRROR ? m.spec_a.rgb : fresnel_conductor(cos_i, m.spec_a.rgb, m.spec_b.rgb);
#if NEARBY_RECURSIVE
        // The object's own rectangle is left out: a surface does not see itself by reflection
        // through its own impostor (pc.material.y = its layer).
        nearby_skip = pc.material.y;
        radiance = F * nearby_radiance(in_position, R);
#else
        radiance = F * environment(R);
#endif
    }
    out_texel = vec4(finite_or_zero(radiance), dot(in_position - pc.origin.xyz, pc.axis.xyz));
}
