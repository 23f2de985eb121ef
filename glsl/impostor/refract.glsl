// Double refraction with a refractor map (Szirmay-Kalos et al. 2005, §4, Fig. 8): for every
// dielectric pixel of the G-buffer,
//   T  = refract(V, N, 1/n)                 first refraction at x
//   l  = Hit(x - c, T, refractor map)       second refraction point (c: refractor centre)
//   N1 = normal stored at l                 from the refractor map
//   T2 = refract(T, N1, n)                  second refraction
//   I  = radiance at Hit(l + c, T2, environment impostor)
// with exact dielectric Fresnel at both interfaces and the reflection at x localized the same
// way (§3). Light reflected inside the refractor is not followed (the paper's Fig. 8 path).
//
// Included by refract.frag (the technique) and refract_oracle.frag (ORACLE_TRACE defined: the
// analysis variant, render.impostor.oracle = "hit", shade_common.glsl's localized_radiance).
// The material kinds a shared environment map leaves out (its own objects: every dielectric,
// src/technique/impostor/distance_impostor.rs):
#define IMPOSTOR_MAP_LEAVES_OUT(k) ((k) == MATERIAL_DIELECTRIC)
#include "shade_common.glsl"
layout(set = 1, binding = BINDING_IMPOSTOR_REFRACTOR) uniform samplerCube refractor_map;
layout(location = 0) in vec2 in_uv;
layout(location = 0) out vec4 out_radiance;

void main() {
    ivec2 px = ivec2(gl_FragCoord.xy);
    float depth = texelFetch(gbuf_depth, px, 0).r;
    if (depth <= 0.0) discard;
    vec4 nm = texelFetch(gbuf_normal, px, 0);
    uint mat = uint(nm.w + 0.5);
    if (material_kind(mat) != MATERIAL_DIELECTRIC) discard;
    if (!impostor_owns(px)) discard;
    GpuMaterial m = materials[mat];
    vec3 V = camera_ray(in_uv);
    vec3 N = normalize(nm.xyz);
    // The camera inside the refractor sees its back faces: one interface, leaving it.
    bool inside = dot(V, N) > 0.0;
    if (inside) N = -N;
    vec3 p = world_from_depth(in_uv, depth);
    float cos_i = clamp(-dot(V, N), 0.0, 1.0);
    vec3 R = reflect(V, N);
    vec3 L_reflected = localized_radiance(p, R);
    vec3 ior = max(m.spec_a.rgb, vec3(1e-6));
    vec3 c = pc.refractor_center.xyz;
    // Equal channels need one refracted path.
    int channels = (ior.r == ior.g && ior.g == ior.b) ? 1 : 3;
    vec3 L = vec3(0.0);
    for (int ch = 0; ch < 3; ++ch) {
        int k = channels == 1 ? 0 : ch;
        float n = ior[k];
        float F1 = fresnel_dielectric(cos_i, inside ? n : 1.0 / n);
        vec3 T = refract(V, N, inside ? n : 1.0 / n);
        vec3 L_t = vec3(0.0);
        float transmitted = 0.0;
        if (dot(T, T) > 0.0) {
            if (inside) {
                L_t = localized_radiance(p, T);
                transmitted = 1.0;
            } else {
                vec3 l = impostor_hit(refractor_map, 3u, p - c, T, ITERATIONS);
                vec3 N1 = textureLod(refractor_map, dot(l, l) > 0.0 ? l : T, 0.0).xyz;
                N1 = dot(N1, N1) > 0.0 ? normalize(N1) : -T;
                if (dot(N1, T) < 0.0) N1 = -N1;          // outward at the exit: along T
                vec3 q = l + c;
                float F2 = fresnel_dielectric(clamp(dot(T, N1), 0.0, 1.0), n);
                vec3 T2 = refract(T, -N1, n);
                if (dot(T2, T2) > 0.0) {
                    vec3 absorbed = exp(-m.spec_b.rgb * length(q - p));
                    L_t = absorbed * localized_radiance(q, T2);
                    transmitted = 1.0 - F2;
                }
            }
        }
        vec3 Lc = F1 * L_reflected + (1.0 - F1) * transmitted * L_t;
        L[ch] = Lc[ch];
        if (channels == 1) { L = Lc; break; }
    }
    out_radiance = vec4(finite_or_zero(L), 1.0);
}
