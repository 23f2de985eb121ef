// What an eikonal view ray meets
// after it leaves the volume, or after the boundary reflects it. Section 5.3 of Ihrke et al.
// 2007 looks up the environment only; for Fig. 7 the paper "replaced the environment map
// lookup by a ray-plane intersection in the fragment shader" and points to Hu and Qin [2007]
// for more complex nearby geometry (§6). Both:
// - the flat diffuse receivers (quads, boxes) as triangles, intersected exactly
//   (Moller & Trumbore 1997; src/technique/eikonal/eikonal_nearby.rs ray_triangle is the CPU twin) and
//   shaded like deferred shading with the light simulation's irradiance (receiver.glsl);
// - the other nearby objects through Hu & Qin 2007 §2.2's impostor rectangles around the
//   volume (glsl/include/nearby.glsl: Fig. 13's rectangle hit, Figs. 16-17's lookup);
// the nearer hit wins; the environment where neither is hit.
// The including shader declares before this file: NEARBY_ITERATIONS, NEARBY_TOLERANCE,
// NEARBY_SEEDS, IMPOSTORS (0: no rectangles), SCATTER and LIGHT_{MIN,MAX}_{X,Y,Z}, and
// includes frame.glsl, lighting.glsl, scatter.glsl and receiver.glsl.
#ifndef EIKONAL_NEARBY_EXIT_GLSL
#define EIKONAL_NEARBY_EXIT_GLSL

#include "nearby.glsl"

// The triangles as RGBA32UI texels (floats by their bits; src/technique/eikonal/eikonal_nearby.rs
// `triangle_buffer_bytes`): texel 0 holds the count in x, triangle i the five texels from
// 1 + 5 i on, GpuTriangle's p0, e1, e2, uv01 and uv2. A texel fetch at a per-lane index is one
// gather on a CPU device (lavapipe), where a storage-buffer load is a loop over the lanes.
layout(set = 1, binding = BINDING_EIKONAL_TRIANGLES) uniform usamplerBuffer eik_triangle_texels;

uint eik_triangle_count() {
    return texelFetch(eik_triangle_texels, 0).x;
}

// Field `f` (0: p0, 1: e1, 2: e2, 3: uv01, 4: uv2) of triangle i.
vec4 eik_triangle(uint i, int f) {
    return uintBitsToFloat(texelFetch(eik_triangle_texels, 1 + 5 * int(i) + f));
}

// The nearest hit t in (t_min, t_max) of o + t d with the triangles: triangle k, barycentrics
// b. Rays parallel to a triangle's plane (|det| <= 1e-12 |e1||e2||d|) miss it.
bool eik_triangle_hit(vec3 o, vec3 d, float t_min, float t_max, out float t, out uint k, out vec2 b) {
    t = t_max;
    k = 0u;
    b = vec2(0.0);
    bool hit = false;
    uint count = min(eik_triangle_count(), MAX_EIKONAL_TRIANGLES);
    for (uint i = 0u; i < count; ++i) {
        vec3 p0 = eik_triangle(i, 0).xyz, e1 = eik_triangle(i, 1).xyz, e2 = eik_triangle(i, 2).xyz;
        vec3 p = cross(d, e2);
        float det = dot(e1, p);
        if (!(abs(det) > 1e-12 * length(e1) * length(e2) * length(d))) continue;
        float inv = 1.0 / det;
        vec3 s = o - p0;
        float b1 = dot(s, p) * inv;
        if (!(b1 >= 0.0 && b1 <= 1.0)) continue;
        vec3 q = cross(s, e1);
        float b2 = dot(d, q) * inv;
        if (!(b2 >= 0.0 && b1 + b2 <= 1.0)) continue;
        float ti = dot(e2, q) * inv;
        if (ti > t_min && ti < t) {
            t = ti;
            k = i;
            b = vec2(b1, b2);
            hit = true;
        }
    }
    return hit;
}

// Radiance of a diffuse surface point towards the viewer (n: unit, facing the viewer).
vec3 eik_surface_radiance(vec3 p, vec3 n, vec3 albedo) {
    if (SCATTER != 0u) {
        vec3 lo = vec3(LIGHT_MIN_X, LIGHT_MIN_Y, LIGHT_MIN_Z), hi = vec3(LIGHT_MAX_X, LIGHT_MAX_Y, LIGHT_MAX_Z);
        return eikonal_receiver(p, n, albedo, lo, hi);
    }
    return diffuse_radiance(p, n, albedo);
}

// The radiance leaving triangle k's hit o + t d towards o (two-sided, flat: the face normal).
vec3 eik_triangle_radiance(uint k, vec3 o, vec3 d, float t, vec2 b) {
    vec4 e1 = eik_triangle(k, 1), e2 = eik_triangle(k, 2), uv01 = eik_triangle(k, 3), uv2 = eik_triangle(k, 4);
    vec3 p = o + max(t, 0.0) * d;
    vec3 n = cross(e1.xyz, e2.xyz);
    n = dot(n, n) > 1e-30 ? normalize(n) : -d;
    if (dot(n, d) > 0.0) n = -n;
    vec2 uv = (1.0 - b.x - b.y) * uv01.xy + b.x * uv01.zw + b.y * uv2.xy;
    vec3 albedo = albedo_at(materials[uint(uv2.z + 0.5)], uv);
    return finite_or_zero(eik_surface_radiance(p, n, albedo));
}

// glsl/include/nearby.glsl nearby_hit (Fig. 13: the closest rectangle first, the next where its texel
// is empty), returning the distance of the surface found instead of falling back to the
// environment.
bool eik_impostor_hit(vec3 P, vec3 Ray, out vec3 color, out float dist) {
    color = vec3(0.0);
    dist = 1e30;
    if (IMPOSTORS == 0u) return false;
    // The one rectangle set around the volume (NearbyImpostors::around); none: no impostors.
    nearby_set = nearby_header.info.y == 0u ? NEARBY_NO_SET : 0u;
    return nearby_hit(P, Ray, color, dist);
}

// What the ray P + t dir (dir unit) meets for t > t_min: the nearer of an exact triangle hit
// and an impostor's surface, else the environment.
vec3 exit_radiance(vec3 P, vec3 dir, float t_min) {
    float t;
    uint k;
    vec2 b;
    bool tri = eik_triangle_hit(P, dir, t_min, 1e30, t, k, b);
    vec3 c;
    float dist;
    if (eik_impostor_hit(P, dir, c, dist) && (!tri || dist < t)) return c;
    if (tri) return eik_triangle_radiance(k, P, dir, t, b);
    return environment(dir);
}
#endif
