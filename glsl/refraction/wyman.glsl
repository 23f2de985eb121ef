// Wyman 2005, "An Approximate Image-Space Approach for Interactive Refraction": refraction
// of a distant environment through two interfaces (§3, and the fragment program of §4).
//   T1 = Refract(V, N1)                            Snell's law at the G-buffer's P1 (§2)
//   d_V = back-layer distance - front distance     along the view ray (§3.1, Fig. 3c)
//   d_N = per-vertex distance along -N, interpolated (§3.1, precomputed on the CPU; the
//         G-buffer's front faces carry it, glsl/gbuffer/gbuffer.frag)
//   d~ = (theta_t / theta_i) d_V + (1 - theta_t / theta_i) d_N   (§3.1, the equation for d~)
//   P2~ = P1 + d~ T1, projected into the back-face normal layer for N2 (§3.2)
//   T2 = Refract(T1, -N2), environment lookup; Fresnel reflection at P1 as the baseline.
// TIR is clamped to the critical angle and P2 outside the silhouette takes N2 from T1 (§3.3).
// The paper's object is one refractor: the back layer holds one array layer per refractor,
// and a pixel reads its own refractor's (the G-buffer's object index picks it).
//
// Included by wyman.frag (the technique) and wyman_oracle.frag (ORACLE_TRACE defined: the
// analysis variant, render.wyman.oracle), which also binds the exact tracer's buffers in set 2
// and replaces the intermediates named by the ORACLE bits by the exact ones.
#include "frame.glsl"
#include "environment.glsl"
#include "fresnel.glsl"
#include "refraction.glsl"
layout(constant_id = 0) const uint DEBUG = 0;
// 1 when some dielectric of the scene has a different ior per channel (as in
// specular/single.frag): lavapipe runs both sides of a per-pixel branch, so the per-channel
// code is compiled out otherwise.
layout(constant_id = 2) const uint DISPERSION = 1;
// 1 when the back layer keeps the furthest back faces (cleared to the far value 1, test LESS),
// 0 for the nearest (cleared to 0, test GREATER): where its depth holds a face, so does its
// normal, and the one-channel depth tells coverage at a quarter of the normal's bytes.
layout(constant_id = 3) const uint BACK_FURTHEST = 1;
// 1 when the scene has one refractor: every dielectric pixel is its own and reads layer 0,
// with no load from the slot buffer. lavapipe loads a storage buffer at a per-pixel index
// lane by lane; that one load was about a tenth of this pass on sphere_env (docs/BENCHMARKS.md).
layout(constant_id = 4) const uint ONE_REFRACTOR = 0;
#ifdef ORACLE_TRACE
// ORACLE_EXIT_POINT | ORACLE_EXIT_NORMAL (src/scene/techniques.rs, WymanOracle).
layout(constant_id = 1) const uint ORACLE = 0;
// The reference's own intersection code and buffers (glsl/reference/trace.glsl), in a set of
// their own: their REF_BINDING_* would meet the G-buffer's and the layers' in set 1.
#define REF_SET 2
#include "../reference/trace.glsl"
#endif
layout(set = 1, binding = BINDING_GBUF_NORMAL) uniform sampler2D gbuf_normal;
layout(set = 1, binding = BINDING_GBUF_DEPTH) uniform sampler2D gbuf_depth;
layout(set = 1, binding = BINDING_GBUF_ALBEDO) uniform sampler2D gbuf_albedo;
layout(set = 1, binding = BINDING_REFR_BACK_NORMAL) uniform sampler2DArray back_normal;
layout(set = 1, binding = BINDING_REFR_BACK_DEPTH) uniform sampler2DArray back_depth;
layout(set = 1, binding = BINDING_REFR_SLOTS, std430) readonly buffer RefractorSlots {
    uint slot_of_object[];
};
layout(location = 0) in vec2 in_uv;
layout(location = 0) out vec4 out_radiance;
layout(location = 1) out vec4 out_p2;
layout(location = 2) out vec4 out_t2;

// This pixel's refractor: its layer of the back-surface array.
int slot;

// As refraction.glsl's layer lookups, on this pixel's refractor's layer: the stored normal,
// 0 off the screen or where the layer holds no surface.
vec3 back_texel(vec2 uv) {
    return on_screen(uv) ? texelFetch(back_normal, ivec3(texel_of(uv), slot), 0).xyz : vec3(0.0);
}

bool covered(vec3 stored_normal) {
    return dot(stored_normal, stored_normal) > 0.25;
}

void main() {
    ivec2 px = ivec2(gl_FragCoord.xy);
    float depth = texelFetch(gbuf_depth, px, 0).r;
    if (depth <= 0.0) discard;
    vec4 nm = texelFetch(gbuf_normal, px, 0);
    uint mat = uint(nm.w + 0.5);
    if (material_kind(mat) != MATERIAL_DIELECTRIC) discard;
    // A dielectric's albedo texel: rgb = d_N's bits in three whole numbers, a = object index.
    vec4 albedo = texelFetch(gbuf_albedo, px, 0);
    uint object = uint(albedo.a + 0.5);
    if (ONE_REFRACTOR != 0u) {
        slot = 0;
    } else {
        if (object >= slot_of_object.length() || slot_of_object[object] == 0xffffffffu) discard;
        slot = int(slot_of_object[object]);
    }
    GpuMaterial m = materials[mat];
    vec3 ior = max(m.spec_a.rgb, vec3(1e-6));
    bool one_ior = DISPERSION == 0u || (ior.r == ior.g && ior.g == ior.b);
    vec3 V = camera_ray(in_uv);
    vec3 N1 = normalize(nm.xyz);
    // A camera inside the refractor sees a back face: one interface, as the baseline
    // (specular/single.frag), with N1 turned to face the camera and the same Fresnel term and
    // two lookups as the two interfaces below. A CPU device (lavapipe) runs a branch's code
    // for every pixel, lanes masked, so a path of its own would add two lookups to each.
    bool from_inside = dot(V, N1) > 0.0;
    if (from_inside) N1 = -N1;
    vec3 P1 = world_from_depth(in_uv, depth);
    float cos_i = clamp(-dot(V, N1), 0.0, 1.0);
    float theta_i = acos(cos_i);
    vec3 L_reflected = environment(reflect(V, N1));

    // d_V: distance between the front and the back surface along the view ray (Fig. 3c).
    float back_z = texelFetch(back_depth, ivec3(px, slot), 0).r;
    bool back_here = BACK_FURTHEST != 0u ? back_z < 1.0 : back_z > 0.0;
    float d_V = back_here ? max(length(world_from_depth(in_uv, back_z) - P1), 0.0) : 0.0;
    float d_N = uintBitsToFloat(uint(albedo.r) | (uint(albedo.g) << 11) | (uint(albedo.b) << 22));
    if (d_N <= 0.0) d_N = d_V;   // open mesh: no far side along -N
    if (!back_here) d_V = d_N;

    // Exact per-channel refraction (dispersion) when the ior is RGB; one path otherwise.
    int channels = one_ior ? 1 : 3;
    vec3 L = vec3(0.0);
    for (int c = 0; c < 3; ++c) {
        int k = channels == 1 ? 0 : c;
        float eta = from_inside ? ior[k] : 1.0 / ior[k];
        vec3 T1 = refract_clamped(V, N1, eta);
        float theta_t = acos(clamp(-dot(N1, T1), -1.0, 1.0));
        // theta_t / theta_i -> eta as theta_i -> 0 (Snell for small angles).
        float ratio = theta_i > 1e-4 ? theta_t / theta_i : eta;
        // Wyman assumes n_t > n_i (ratio <= 1); for n_t < n_i the same formula
        // extrapolates beyond d_V, kept non-negative.
        float d = max(ratio * d_V + (1.0 - ratio) * d_N, 0.0);
        vec3 P2 = P1 + d * T1;
#ifdef ORACLE_TRACE
        // The exact exit of T1: the reference's closest hit from P1, offset inside by its ray
        // epsilon (offset_origin's), and its shading normal turned to face out along T1 (the
        // normal interaction_at refracts about, negated). No hit (an open mesh): the paper's.
        vec3 P2_exact = P2, N2_exact = vec3(0.0);
        float d_exact = d;
        bool exact = false;
        if (ORACLE != 0u) {
            float eps = ref.proj.z * (1.0 + max(max(abs(P1.x), abs(P1.y)), abs(P1.z)) / max(ref.proj.w, 1e-30));
            vec3 o = P1 - N1 * eps;
            Hit h = trace(o, T1, 3.4e38);
            if (h.kind != 0u) {
                Surface s = surface_at(o, T1, h);
                exact = true;
                P2_exact = s.p;
                d_exact = length(s.p - P1);
                N2_exact = dot(T1, s.ng) > 0.0 ? s.ns : -s.ns;
            }
        }
        // §3.1: P2~ = P1 + d~ T1 (and d~ in the absorption) replaced by the exact exit.
        if (exact && (ORACLE & ORACLE_EXIT_POINT) != 0u) {
            P2 = P2_exact;
            d = d_exact;
        }
#endif
        // One fetch of P2's texel serves the coverage test and N2.
        vec3 n2 = back_texel(project_uv(P2));
        bool inside = covered(n2);
        vec3 N2 = inside ? normalize(n2) : silhouette_normal(T1);
#ifdef ORACLE_TRACE
        // §3.2: N2 from the back-normal layer at P2's texel (or §3.3's silhouette normal)
        // replaced by the exact normal at T1's exit.
        if (exact && (ORACLE & ORACLE_EXIT_NORMAL) != 0u) {
            N2 = N2_exact;
            inside = true;
        }
#endif
        // Leaving the object: the normal facing T1 is -N2, and eta = n_refractor / n_outside.
        vec3 T2 = refract_clamped(T1, -N2, ior[k]);
        // From inside, T1 leaves the refractor (under TIR F = 1 and T1's lookup adds 0).
        vec3 absorb = from_inside ? vec3(1.0) : exp(-m.spec_b.rgb * d);
        vec3 L_t = environment(from_inside ? T1 : T2) * absorb;
        float F = fresnel_dielectric(cos_i, eta);
        if (channels == 1) {
            L = F * L_reflected + (1.0 - F) * L_t;
        } else {
            L[c] = F * L_reflected[c] + (1.0 - F) * L_t[c];
        }
        if (c == 0 && DEBUG != 0) {
            // No exit (kind 0) from inside.
            out_p2 = from_inside ? vec4(0.0) : vec4(P2, inside ? 1.0 : 3.0);
            out_t2 = from_inside ? vec4(0.0) : vec4(T2, d);
        }
        if (channels == 1) break;
    }
    out_radiance = vec4(finite_or_zero(L), 1.0);
}
