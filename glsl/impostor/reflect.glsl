// Localized reflections with a distance impostor (Szirmay-Kalos et al. 2005, §3): for every
// mirror or conductor pixel of the G-buffer, R = reflect(V, N), l = Hit(x, R), I = the
// impostor's radiance towards l, times Fresnel (the paper's approximation or exact).
//
// Included by reflect.frag (the technique) and reflect_oracle.frag (ORACLE_TRACE defined: the
// analysis variant, render.impostor.oracle = "hit", shade_common.glsl's localized_radiance).
// The material kinds a shared environment map leaves out (its own objects: every mirror and
// conductor, src/technique/impostor/distance_impostor.rs):
#define IMPOSTOR_MAP_LEAVES_OUT(k) ((k) == MATERIAL_MIRROR || (k) == MATERIAL_CONDUCTOR)
#include "shade_common.glsl"
layout(location = 0) in vec2 in_uv;
layout(location = 0) out vec4 out_radiance;

void main() {
    ivec2 px = ivec2(gl_FragCoord.xy);
    float depth = texelFetch(gbuf_depth, px, 0).r;
    if (depth <= 0.0) discard;
    vec4 nm = texelFetch(gbuf_normal, px, 0);
    uint mat = uint(nm.w + 0.5);
    uint kind = material_kind(mat);
    if (kind != MATERIAL_MIRROR && kind != MATERIAL_CONDUCTOR) discard;
    if (!impostor_owns(px)) discard;
    vec3 V = camera_ray(in_uv);
    vec3 N = normalize(nm.xyz);
    if (dot(V, N) > 0.0) N = -N;
    vec3 p = world_from_depth(in_uv, depth);
    vec3 R = reflect(V, N);
    vec3 L = metal_reflectance(materials[mat], kind, clamp(dot(N, R), 0.0, 1.0)) * localized_radiance(p, R);
    out_radiance = vec4(finite_or_zero(L), 1.0);
}
