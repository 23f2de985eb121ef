#version 450
// Single-interface refraction of nearby geometry through a water surface
// (src/technique/refraction/refraction_water.rs). At each of the surface's pixels the G-buffer
// gives the point the ray through the pixel's centre meets and its interpolated normal (both
// follow the window's water animation); the ray splits there by exact Fresnel, and each branch
// goes on in a straight line, in the water or in the air, through the exact tracer's BVH
// (glsl/reference/trace.glsl) until it meets a diffuse receiver or leaves to the environment.
// A receiver is shaded like deferred shading (glsl/include/lighting.glsl: direct light with
// the shadow maps, which hold the water, and the environment's irradiance) plus the caustic
// that the selected caustic technique put on it (glsl/include/caustic_lookup.glsl): under the
// water the sun's light arrives as that caustic only (Shah et al. 2007, Fig. 1 and §III.E,
// single-surface refraction). The radiance leaving the water is scaled by (n_i/n_t)^2
// (SCENES.md, "Light transport measured") and attenuated by Beer-Lambert along the path in
// the water.
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

// RT0 of the G-buffer: xyz = normal, w = material index; at BINDING_WATER_GBUF_NORMAL, since
// BINDING_GBUF_NORMAL is the tracer's REF_BINDING_UNIFORMS here.
layout(set = 1, binding = BINDING_WATER_GBUF_NORMAL) uniform sampler2D gbuf_normal;
layout(set = 1, binding = BINDING_GBUF_DEPTH) uniform sampler2D gbuf_depth;
// The environment's SH coefficients as seen from under the water surface at rest (Snell's
// window, Fresnel transmittance: src/frame/gpu_scene.rs, environment_sh_below): a receiver in
// the water gets its environment light only through the surface.
layout(set = 1, binding = BINDING_WATER_SKY, std430) readonly buffer WaterSky { vec4 sky_below[9]; };
layout(location = 0) in vec2 in_uv;
layout(location = 0) out vec4 out_radiance;

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
    vec3 L = albedo / PI * lit_irradiance(s.p, n, ambient) + caustic_radiance(s.p, n, object_of(h.kind, h.prim), albedo);
    return in_water ? exp(-sigma * h.t) * L : L;
}

void main() {
    ivec2 px = ivec2(gl_FragCoord.xy);
    float depth = texelFetch(gbuf_depth, px, 0).r;
    if (depth <= 0.0) discard;
    vec4 nm = texelFetch(gbuf_normal, px, 0);
    Surface s;
    s.material = uint(nm.w + 0.5);
    GpuMaterial m = materials[s.material];
    if (kind_of(m) != MATERIAL_DIELECTRIC) discard;
    s.p = world_from_depth(in_uv, depth);
    s.ns = normalize(nm.xyz);
    s.ng = s.ns;
    s.st = vec2(0.0);

    vec3 d = camera_ray(in_uv);
    Interaction x;
    interaction_at(s, d, distance(frame.camera_position.xyz, s.p), -1, true, x);
    // Entering the water the refracted branch travels in it; leaving it, in the air.
    bool entering = dot(d, s.ng) < 0.0;
    vec3 L = x.weight * x.F * radiance_along(offset_origin(s, x.reflected), x.reflected, !entering, m.spec_b.rgb);
    if (x.transmits) {
        L += x.weight * (1.0 - x.F) * x.scale * radiance_along(offset_origin(s, x.refracted), x.refracted, entering, m.spec_b.rgb);
    }
    out_radiance = vec4(finite_or_zero(L), 1.0);
}
