#version 450
// TEX_i / TEX_DEPTH_i of Hu & Qin 2007 §2.2.1 (Fig. 13): the object's radiance as the
// camera would see it (direct light with shadow maps + environment irradiance, the same
// function as deferred shading: glsl/include/lighting.glsl), and the depth that the
// iterative lookup of Fig. 16 compares against, as the axial distance from O_R along the
// projection direction (linear in the ortho z, in world units).
#include "frame.glsl"
#include "lighting.glsl"
#include "push.glsl"
layout(location = 0) in vec3 in_position;
layout(location = 1) in vec3 in_normal;
layout(location = 2) in vec2 in_checker_uv;
// RT0 (RGBA32F): rgb = outgoing radiance (HDR); a = dot(p - O_R, n_i).
layout(location = 0) out vec4 out_texel;
void main() {
    uint mat = pc.material.x;
    vec3 n = in_normal;
    float len = length(n);
    n = len > 1e-20 ? n / len : -pc.axis.xyz;
    // Two-sided diffuse: shade the side the projection sees (it looks along +axis).
    if (dot(n, pc.axis.xyz) > 0.0) n = -n;
    vec3 radiance = vec3(0.0);
    if (material_kind(mat) == MATERIAL_DIFFUSE) {
        radiance = diffuse_radiance(in_position, n, albedo_at(materials[mat], in_checker_uv));
    }
    out_texel = vec4(radiance, dot(in_position - pc.origin.xyz, pc.axis.xyz));
}
