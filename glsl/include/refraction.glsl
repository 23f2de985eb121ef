// Shared by the image-space refraction passes (refraction/wyman.frag, refraction/hu_qin.frag):
// projection to the refractor layers, their lookups, and refraction with Wyman's TIR clamp.
#ifndef PRISM_REFRACTION_GLSL
#define PRISM_REFRACTION_GLSL
#include "frame.glsl"
#include "environment.glsl"
#include "fresnel.glsl"

// uv (0..1, row 0 at the top) of a world point: the inverse of view_ray()/camera_ray().
vec2 project_uv(vec3 p) {
    vec4 clip = frame.view_proj * vec4(p, 1.0);
    return clip.xy / clip.w * 0.5 + 0.5;
}

// View-space distance along -z of a world point; layer depths hold near / that distance.
float view_depth(vec3 p) {
    return -(frame.view * vec4(p, 1.0)).z;
}

bool on_screen(vec2 uv) {
    return all(greaterThanEqual(uv, vec2(0.0))) && all(lessThan(uv, vec2(1.0)));
}

ivec2 texel_of(vec2 uv) {
    return clamp(ivec2(uv * frame.viewport.xy), ivec2(0), ivec2(frame.viewport.xy) - 1);
}

// A layer texel is covered where a refractor wrote its unit normal (cleared to 0).
bool layer_covered(sampler2D layer_normal, vec2 uv) {
    if (!on_screen(uv)) return false;
    vec3 n = texelFetch(layer_normal, texel_of(uv), 0).xyz;
    return dot(n, n) > 0.25;
}

// The same test on a layer's depth, where the layer is kept nearest-first in reversed Z
// (cleared to 0, depth test GREATER: `Front`, `BackNearest`): a refractor's fragment writes
// near / distance > 0 with its normal, so the two tests agree texel for texel, and the
// one-channel depth is a quarter of the RGBA32F normal's bytes per lookup.
bool layer_depth_covered(sampler2D layer_depth, vec2 uv) {
    if (!on_screen(uv)) return false;
    return texelFetch(layer_depth, texel_of(uv), 0).r > 0.0;
}

// View-space distance along -z of the layer's surface at uv (reversed Z: near / depth).
float layer_view_depth(sampler2D layer_depth, vec2 uv) {
    return frame.clip.x / max(texelFetch(layer_depth, texel_of(uv), 0).r, 1e-30);
}

vec3 layer_normal_at(sampler2D layer_normal, vec2 uv) {
    return normalize(texelFetch(layer_normal, texel_of(uv), 0).xyz);
}

// The camera's look-at direction L_at (world space).
vec3 look_at_dir() {
    return -normalize(frame.inv_view[2].xyz);
}

// Refraction of unit I at unit normal N (facing I) with eta = n_i / n_t. Under total
// internal reflection the incident angle is clamped to the critical angle, so that the ray
// "refracts" tangent to the surface (Wyman 2005, §3.3): T is I's component perpendicular to N.
vec3 refract_clamped(vec3 I, vec3 N, float eta) {
    vec3 T = refract(I, N, eta);
    if (dot(T, T) > 0.0) return T;
    vec3 t = I - dot(I, N) * N;
    float len = length(t);
    return len > 1e-12 ? t / len : -N;
}

// Wyman 2005 §3.3: when P2 projects outside the refractor's silhouette, N2 is T1 projected
// onto the plane perpendicular to L_at: N2 = T1 - (L_at . T1) L_at (outward normal).
vec3 silhouette_normal(vec3 T1) {
    vec3 L = look_at_dir();
    vec3 n = T1 - dot(L, T1) * L;
    float len = length(n);
    return len > 1e-12 ? n / len : T1;
}

#endif
