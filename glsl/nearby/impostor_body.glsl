// TEX_i / TEX_DEPTH_i of Hu & Qin 2007 §2.2.1 (Fig. 13): the object's radiance as the
// camera would see it (direct light with shadow maps + environment irradiance, the same
// function as deferred shading: glsl/include/lighting.glsl), and the depth that the
// iterative lookup of Fig. 16 compares against, as the axial distance from O_R along the
// projection direction (linear in the ortho z, in world units).
// A specular OBJ_k (§2.2.1: "If OBJ_k in Fig. 12 is a reflector or a refractor, we render
// TEX_k using the above method") reflects - and a dielectric also refracts - the parallel
// projection's view direction: at recursion level 0 it sees the environment only
// (impostor.frag); at level >= 1 (impostor_recursive.frag) the impostors of the level below
// of its own rectangle set (which holds OBJ_R). Included by both with NEARBY_RECURSIVE 0 or 1.
#include "frame.glsl"
#include "lighting.glsl"
#include "fresnel.glsl"
#include "refraction.glsl"
#include "push.glsl"
#if NEARBY_RECURSIVE
// The lookup of the level below: the same correction as refraction_hu_qin (constants 0..2).
layout(constant_id = 0) const uint NEARBY_ITERATIONS = 3;
layout(constant_id = 1) const float NEARBY_TOLERANCE = 1e-3;
layout(constant_id = 2) const uint NEARBY_SEEDS = 8;
#include "nearby.glsl"
#endif
layout(location = 0) in vec3 in_position;
layout(location = 1) in vec3 in_normal;
layout(location = 2) in vec2 in_checker_uv;
// RT0 (RGBA32F): rgb = outgoing radiance (HDR) towards O_R; a = dot(p - O_R, n_i).
layout(location = 0) out vec4 out_texel;

// What OBJ_k sees from P along unit dir.
vec3 seen_from(vec3 P, vec3 dir) {
#if NEARBY_RECURSIVE
    // Level n: OBJ_k's own rectangles (OBJ_k is not among them: a surface does not see
    // itself through its own impostor) at level n - 1; none -> the environment.
    nearby_set = pc.material.z;
    return nearby_radiance(P, dir);
#else
    return environment(dir);
#endif
}

// A dielectric OBJ_k as the main pass shows OBJ_R (glsl/refraction/hu_qin.frag), with the
// projection's eye ray V = +axis: the Fresnel-weighted reflection at P1 and refraction through
// two interfaces. P1 and N1 are this fragment (the nearest surface in the parallel
// projection). Simplification of the second interface (documented in docs/scene-format.md):
// the refracted ray T1 leaves OBJ_k where it leaves OBJ_k's bounding sphere (O_k, d_k), the
// rectangle's own centre and half-size, with that sphere's normal N2. Exact for a ball (up to
// its tessellation); for other shapes the exit is further out than the true one. The paper's
// exit search (§2.1, Figs. 5-9) would need OBJ_k's back and front depth/normal layers rendered
// in every rectangle's parallel projection: one more pass per specular rectangle and level.
vec3 dielectric_texel(vec3 P1, vec3 N1, Material m) {
    vec3 V = pc.axis.xyz;
    vec3 ior = max(m.spec_a.rgb, vec3(1e-6));
    float cos_i = clamp(-dot(V, N1), 0.0, 1.0);
    vec3 L_r = seen_from(P1, reflect(V, N1));
    // Exact per-channel refraction (dispersion) when the ior is RGB; one path otherwise.
    int channels = (ior.r == ior.g && ior.g == ior.b) ? 1 : 3;
    vec3 L = vec3(0.0);
    for (int c = 0; c < channels; ++c) {
        float F = fresnel_dielectric(cos_i, 1.0 / ior[c]);
        vec3 T1 = refract(V, N1, 1.0 / ior[c]);
        vec3 L_t = vec3(0.0);
        if (dot(T1, T1) > 0.0) {
            // Far intersection of P1 + d T1 with the sphere: P1 lies inside it (every vertex
            // is within d_k of O_k, and the faces between them too), so the root is >= 0.
            vec3 o = P1 - pc.sphere.xyz;
            float b = dot(o, T1);
            float d = max(-b + sqrt(max(b * b - (dot(o, o) - pc.sphere.w * pc.sphere.w), 0.0)), 0.0);
            vec3 P2 = P1 + d * T1;
            vec3 N2 = P2 - pc.sphere.xyz;
            float len = length(N2);
            N2 = len > 1e-20 ? N2 / len : T1;
            // Leaving: eta = n_k / 1; TIR clamped to the critical angle as the main pass does.
            vec3 T2 = refract_clamped(T1, -N2, ior[c]);
            L_t = seen_from(P2, T2) * exp(-m.spec_b.rgb * d);
        }
        vec3 Lc = F * L_r + (1.0 - F) * L_t;
        if (channels == 1) {
            L = Lc;
        } else {
            L[c] = Lc[c];
        }
    }
    return L;
}

void main() {
    uint mat = pc.material.x;
    uint kind = material_kind(mat);
    vec3 n = in_normal;
    float len = length(n);
    n = len > 1e-20 ? n / len : -pc.axis.xyz;
    // Two-sided: shade the side the projection sees (it looks along +axis).
    if (dot(n, pc.axis.xyz) > 0.0) n = -n;
    vec3 radiance = vec3(0.0);
    if (kind == MATERIAL_DIFFUSE) {
        radiance = diffuse_radiance(in_position, n, albedo_at(materials[mat], in_checker_uv));
    } else if (kind == MATERIAL_MIRROR || kind == MATERIAL_CONDUCTOR) {
        // The parallel projection's eye ray is +axis everywhere.
        vec3 R = reflect(pc.axis.xyz, n);
        float cos_i = clamp(-dot(pc.axis.xyz, n), 0.0, 1.0);
        Material m = materials[mat];
        vec3 F = kind == MATERIAL_MIRROR ? m.spec_a.rgb : fresnel_conductor(cos_i, m.spec_a.rgb, m.spec_b.rgb);
        radiance = F * seen_from(in_position, R);
    } else if (kind == MATERIAL_DIELECTRIC) {
        radiance = dielectric_texel(in_position, n, materials[mat]);
    }
    out_texel = vec4(finite_or_zero(radiance), dot(in_position - pc.origin.xyz, pc.axis.xyz));
}
