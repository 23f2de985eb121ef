#version 450
// The photons' caustic on the diffuse surfaces seen directly (render.caustics = "raytrace",
// src/technique/raytrace.rs), added to deferred shading's radiance: every pixel the G-buffer
// gives to a diffuse object traces its centre ray exactly, as the refraction and reflection
// passes do (glsl/reference/trace.glsl), and the diffuse surface it meets first gathers this
// frame's photons (caustic.glsl). Only the caustic is added: direct and environment light are
// deferred shading's, as with the other caustics techniques.
#include "frame.glsl"
#include "environment.glsl"
#define REF_SET 1
#include "../reference/volume.glsl"
#include "caustic.glsl"

// RT1 of the G-buffer: a = object index; its binding and the depth's are free in set 1
// (raytrace.frag says why).
layout(set = 1, binding = BINDING_GBUF_ALBEDO) uniform sampler2D gbuf_albedo;
layout(set = 1, binding = BINDING_GBUF_DEPTH) uniform sampler2D gbuf_depth;
layout(location = 0) in vec2 in_uv;
layout(location = 0) out vec4 out_radiance;

void main() {
    ivec2 px = ivec2(gl_FragCoord.xy);
    if (texelFetch(gbuf_depth, px, 0).r <= 0.0) discard;
    uint object = uint(texelFetch(gbuf_albedo, px, 0).a + 0.5);
    if (material_kind(object_material(object)) != MATERIAL_DIFFUSE) discard;
    vec3 o = frame.camera_position.xyz, d = camera_ray(in_uv);
    Hit h = trace(o, d, 3.4e38);
    float tv;
    // Seen through a graded-index volume, or not a diffuse surface after all (the tessellated
    // silhouette of an exact sphere): no caustic here.
    if (h.kind == 0u || region_entry(o, d, h.t, tv)) discard;
    Surface s = surface_at(o, d, h);
    if (kind_of(materials[s.material]) != MATERIAL_DIFFUSE) discard;
    vec3 n = dot(d, s.ns) < 0.0 ? s.ns : -s.ns;
    // Additive: alpha 0 keeps the target's.
    out_radiance = vec4(finite_or_zero(caustic_at(s, d, n, h.t)), 0.0);
}
