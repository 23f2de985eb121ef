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

// The procedural grid of SCENES.md, as src/scene/environment.rs `grid_radiance` defines it
// (the same constants, and the same angles): lines within GRID_LINE_HALF_WIDTH_DEG of every
// multiple of GRID_SPACING_DEG of longitude atan2(x, -z) and latitude 90 - acos(y), over a
// sky mixed from horizon to zenith by d.y and a ground. Evaluated per lookup, with no filter:
// a camera ray samples the formula at its pixel's centre, as SCENES.md defines a pixel (a
// 1-degree line is several pixels wide at 512^2 with a 40-degree field of view).
bool grid_near_line(float a) {
    float m = mod(a, GRID_SPACING_DEG);
    return m <= GRID_LINE_HALF_WIDTH_DEG || m >= GRID_SPACING_DEG - GRID_LINE_HALF_WIDTH_DEG;
}

vec3 grid_radiance(vec3 d) {
    float lon = degrees(atan(d.x, -d.z));
    // 90 - acos(y) as atan2(y, |xz|), the same angle: lavapipe's acos is an approximation
    // about 0.01 degree off at 15 degrees of latitude, which moved the +15-degree line's edges
    // by a pixel at 256^2; its atan is as accurate as the CPU's.
    float lat = degrees(atan(d.y, length(d.xz)));
    if (grid_near_line(lon) || grid_near_line(lat)) return vec3(GRID_LINE_RADIANCE);
    return d.y >= 0.0 ? mix(GRID_SKY_HORIZON, GRID_SKY_ZENITH, d.y) : GRID_GROUND;
}

// Radiance from direction d: the lat-long map, or the grid's formula when the map is the 1x1
// stand-in whose alpha is ENVIRONMENT_GRID_ALPHA (src/frame/gpu_scene.rs).
vec3 environment_lookup(sampler2D map, vec3 d) {
    d = normalize(d);
    if (textureSize(map, 0) == ivec2(1)) {
        vec4 c = texelFetch(map, ivec2(0), 0);
        return c.a == ENVIRONMENT_GRID_ALPHA ? grid_radiance(d) : c.rgb;
    }
    return textureLod(map, dir_to_latlong(d), 0.0).rgb;
}
#endif
