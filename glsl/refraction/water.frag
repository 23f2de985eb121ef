#version 450
// Single-interface refraction of nearby geometry through a water surface
// (src/technique/refraction/refraction_water.rs). The ray through the pixel's centre meets the
// surface (the tracer's exact triangles, glsl/reference/trace.glsl: the G-buffer only says which
// pixels are the water's), splits there by exact Fresnel, and each branch goes on in a straight
// line, in the water or in the air, until it meets a diffuse receiver or leaves to the
// environment. A receiver is shaded like deferred shading (glsl/include/lighting.glsl: direct
// light with the shadow maps, which hold the water, and the environment's irradiance) plus the
// caustic that the selected caustic technique put on it (glsl/include/caustic_lookup.glsl):
// under the water the sun's light arrives as that caustic only (Shah et al. 2007, Fig. 1 and
// §III.E, single-surface refraction). The radiance leaving the water is scaled by
// (n_i/n_t)^2 (SCENES.md, "Light transport measured") and attenuated by Beer-Lambert along the
// path in the water.
#include "frame.glsl"
#include "environment.glsl"
#include "lighting.glsl"
#define REF_SET 1
#include "../reference/trace.glsl"

// caustic_lookup.glsl's selection: src/technique/baseline/deferred_shading.rs, CausticReads.
layout(constant_id = 0) const uint CAUSTICS = 0;
layout(constant_id = 1) const uint CAUSTIC_FILTER = 0;
layout(constant_id = 2) const uint PHOTON_RECTS = 0;
layout(constant_id = 3) const uint PHOTON_MODE = 0;
#include "caustic_lookup.glsl"

// RT1 of the G-buffer: a = object index. The depth says where something was drawn.
layout(set = 1, binding = BINDING_GBUF_ALBEDO) uniform sampler2D gbuf_albedo;
layout(set = 1, binding = BINDING_GBUF_DEPTH) uniform sampler2D gbuf_depth;
// The environment's SH coefficients as seen from under the water surface at rest (Snell's
// window, Fresnel transmittance: src/frame/gpu_scene.rs, environment_sh_below): a receiver in
// the water gets its environment light only through the surface.
layout(set = 1, binding = BINDING_WATER_SKY, std430) readonly buffer WaterSky { vec4 sky_below[9]; };
layout(location = 0) in vec2 in_uv;
layout(location = 0) out vec4 out_radiance;

uint hit_object(Hit h) {
    return h.kind == 2u ? spheres[h.prim].info.x : triangles[h.prim].w;
}

// Radiance arriving at o along the unit direction d from the first surface met: a diffuse
// receiver's shading, else the environment in that direction (a second specular surface is not
// followed: the technique models one interface). `in_water`: the ray travels in the water,
// with absorption coefficient `sigma`.
vec3 radiance_along(vec3 o, vec3 d, bool in_water, vec3 sigma) {
    Hit h = trace(o, d, 3.4e38);
    if (h.kind == 0u) return environment(d);
    Surface s = surface_at(o, d, h);
    if (kind_of(materials[s.material]) != MATERIAL_DIFFUSE) return environment(d);
    vec3 n = dot(d, s.ns) < 0.0 ? s.ns : -s.ns;
    vec3 albedo = albedo_at(materials[s.material], s.st);
    vec3 ambient;
    if (in_water) {
        vec3 c[9];
        for (int k = 0; k < 9; ++k) c[k] = sky_below[k].rgb;
        ambient = sh_irradiance(c, n);
    } else {
        ambient = environment_irradiance(n);
    }
    vec3 L = albedo / PI * lit_irradiance(s.p, n, ambient) + caustic_radiance(s.p, n, hit_object(h), albedo);
    return in_water ? exp(-sigma * h.t) * L : L;
}

void main() {
    ivec2 px = ivec2(gl_FragCoord.xy);
    if (texelFetch(gbuf_depth, px, 0).r <= 0.0) discard;
    uint object = uint(texelFetch(gbuf_albedo, px, 0).a + 0.5);
    if (material_kind(object_material[object]) != MATERIAL_DIELECTRIC) discard;

    vec3 o = frame.camera_position.xyz, d = camera_ray(in_uv);
    Hit h = trace(o, d, 3.4e38);
    // The rasterised surface covers a pixel whose centre ray misses the exact one: what the
    // ray meets instead.
    if (h.kind == 0u) {
        out_radiance = vec4(finite_or_zero(environment(d)), 1.0);
        return;
    }
    Surface s = surface_at(o, d, h);
    GpuMaterial m = materials[s.material];
    Interaction x;
    if (kind_of(m) != MATERIAL_DIELECTRIC || !interaction_at(s, d, h.t, -1, true, x)) {
        out_radiance = vec4(finite_or_zero(radiance_along(o, d, false, vec3(0.0))), 1.0);
        return;
    }
    // Entering the water the refracted branch travels in it; leaving it, in the air.
    bool entering = dot(d, s.ng) < 0.0;
    vec3 L = x.weight * x.F * radiance_along(offset_origin(s, x.reflected), x.reflected, !entering, m.spec_b.rgb);
    if (x.transmits) {
        L += x.weight * (1.0 - x.F) * x.scale * radiance_along(offset_origin(s, x.refracted), x.refracted, entering, m.spec_b.rgb);
    }
    out_radiance = vec4(finite_or_zero(L), 1.0);
}
