// Definitions shared by the raster passes and the reference path tracer.
#ifndef PRISM_COMMON_GLSL
#define PRISM_COMMON_GLSL
#include "prism_shared.glsl"

const float PI = 3.14159265358979323846;


uint kind_of(GpuMaterial m) { return uint(m.albedo_a.w + 0.5); }

// Diffuse albedo at checker coordinates st (SCENES.md: colour a where
// floor(s/size) + floor(t/size) is even).
vec3 albedo_at(GpuMaterial m, vec2 st) {
    if (m.albedo_b.w <= 0.0) return m.albedo_a.rgb;
    vec2 c = floor(st / m.albedo_b.w);
    return (mod(c.x + c.y, 2.0) == 0.0) ? m.albedo_a.rgb : m.albedo_b.rgb;
}

// Replace NaN/Inf by zero: no NaN or Inf may ever reach a pixel.
vec3 finite_or_zero(vec3 v) {
    return mix(v, vec3(0.0), bvec3(isnan(v.x) || isinf(v.x), isnan(v.y) || isinf(v.y), isnan(v.z) || isinf(v.z)));
}

// Latitude-longitude mapping of SCENES.md: u = 0.5 + atan2(x, -z) / (2 pi), v = acos(y) / pi,
// (0, 0) the top-left texel.
vec2 dir_to_latlong(vec3 d) {
    return vec2(0.5 + atan(d.x, -d.z) / (2.0 * PI), acos(clamp(d.y, -1.0, 1.0)) / PI);
}

vec3 environment_lookup(sampler2D map, vec3 d) {
    return textureLod(map, dir_to_latlong(normalize(d)), 0.0).rgb;
}
#endif
