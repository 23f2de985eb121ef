// Definitions shared by the raster passes and the reference path tracer.
#ifndef PRISM_COMMON_GLSL
#define PRISM_COMMON_GLSL
#include "prism_shared.glsl"

// The scene's environment kind, light count and light kinds (src/technique/mod.rs
// `scene_specialization` sets them for the shading passes). A CPU device (lavapipe) runs both
// sides of every branch with lanes masked, and a loop's body at least once, so a lookup that
// chose the environment kind or the light kind per call paid for every kind, and a scene
// without lights paid for one light's shadow lookups: on sphere_nearby (one point light, a
// constant environment) deferred shading took 2.5x its specialised time (docs/BENCHMARKS.md).
// The defaults (*_ANY) decide from the frame's data, for the pipelines that do not set them.
layout(constant_id = 200) const uint ENVIRONMENT = ENVIRONMENT_ANY;
layout(constant_id = 201) const uint LIGHT_COUNT = LIGHT_COUNT_ANY;
layout(constant_id = 202) const uint LIGHT_KINDS = LIGHT_KINDS_ANY;

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
// stand-in whose alpha is ENVIRONMENT_GRID_ALPHA (src/frame/gpu_scene.rs), or the 1x1 map's
// texel (a constant environment).
vec3 environment_lookup(sampler2D map, vec3 d) {
    d = normalize(d);
    if (ENVIRONMENT == ENVIRONMENT_CONSTANT) return texelFetch(map, ivec2(0), 0).rgb;
    if (ENVIRONMENT == ENVIRONMENT_GRID) return grid_radiance(d);
    if (ENVIRONMENT == ENVIRONMENT_ANY && textureSize(map, 0) == ivec2(1)) {
        vec4 c = texelFetch(map, ivec2(0), 0);
        return c.a == ENVIRONMENT_GRID_ALPHA ? grid_radiance(d) : c.rgb;
    }
    return textureLod(map, dir_to_latlong(d), 0.0).rgb;
}
#endif
