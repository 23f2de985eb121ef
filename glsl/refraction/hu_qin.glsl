// Hu & Qin 2007, "Interactive Approximate Rendering of Reflections, Refractions, and
// Caustics", §2.1: refraction of the environment through two interfaces without
// preprocessing (Fig. 4), for n_t > n_i and n_t < n_i alike.
//   T1 at the G-buffer's P1; binary search along t1 (T1 projected to the buffer) for the
//   dividing pixel p_e (Fig. 6, 7); P_e unprojected; theta_1 > theta_2 -> P2 on a front-facing
//   surface, else back-facing (§2.1.2, Fig. 5); the iterative d_T search against that depth
//   layer (§2.1.3, Fig. 8, 9); N2 from the matching normal layer (§2.1.4); T2; environment.
// Section 4's acceleration (ASSUME_BACK_FACING): skip the binary search, assume back-facing,
// and switch to the front-facing layer when P2 leaves the refractor's silhouette.
// §2.2: R (at P1) and T2 (at P2) see the nearby objects through their impostor rectangles
// (glsl/include/nearby.glsl, Figs. 13, 16, 17), the environment map where none is hit; the
// two are weighted by the dielectric Fresnel term. Each dielectric is its own OBJ_R with its
// own rectangle set (§2.2.1), picked by the G-buffer's object index.
//
// Included by hu_qin.frag (the technique) and hu_qin_oracle.frag (ORACLE_TRACE defined: the
// analysis variant, render.hu_qin.oracle), which also binds the exact tracer's buffers in set 2
// and replaces the intermediates named by the ORACLE bits by the exact ones.
#include "frame.glsl"
#include "environment.glsl"
#include "fresnel.glsl"
#include "refraction.glsl"
layout(constant_id = 0) const uint DEBUG = 0;
layout(constant_id = 1) const uint SEARCH_STEPS = 8;
layout(constant_id = 2) const float TOLERANCE = 1e-4;
layout(constant_id = 3) const uint MAX_ITERATIONS = 32;
layout(constant_id = 4) const uint ASSUME_BACK_FACING = 0;
// §2.2.2: correction iterations of Fig. 16 (0 = Fig. 13), tolerance (fraction of d_i), and
// the seeds of Fig. 17.
layout(constant_id = 5) const uint NEARBY_ITERATIONS = 3;
layout(constant_id = 6) const float NEARBY_TOLERANCE = 1e-3;
layout(constant_id = 7) const uint NEARBY_SEEDS = 8;
// render.hu_qin.d_t_step: Fig. 9's step (D_T_STEP_PAPER) or that step over |T1 . V| (D_T_STEP_NEWTON).
layout(constant_id = 8) const uint D_T_STEP = D_T_STEP_PAPER;
// render.hu_qin.d_t_bracket: 1 keeps the d_T iteration inside the interval where its residual
// changes sign (glsl/include/hu_qin_exit.glsl).
layout(constant_id = 13) const uint D_T_BRACKET = 1;
// render.hu_qin.nearby_lookup: Fig. 13's closest rectangle (NEARBY_LOOKUP_PAPER) or the nearest
// corrected surface over all rectangles (NEARBY_LOOKUP_NEAREST), glsl/include/nearby.glsl.
layout(constant_id = 9) const uint NEARBY_LOOKUP = NEARBY_LOOKUP_PAPER;
// 0 when no rectangle exists (no other object, or render.hu_qin.nearby = false): R and T2 see
// the environment only. A specialisation constant rather than the empty rectangle list's own
// test, because a CPU device (lavapipe) runs both sides of a per-pixel branch with lanes
// masked: the lookup's code must not be in the shader when nothing can be looked up.
layout(constant_id = 11) const uint NEARBY = 1;
// 1 when some dielectric of the scene has a different ior per channel (as in
// specular/single.frag): lavapipe runs both sides of a per-pixel branch, so the per-channel
// code is compiled out otherwise.
layout(constant_id = 12) const uint DISPERSION = 1;
#include "nearby.glsl"

// What a ray leaving OBJ_R at P sees: the nearby objects (§2.2) or the environment map.
vec3 seen_from(vec3 P, vec3 Ray) {
    return NEARBY != 0u ? nearby_radiance(P, Ray) : environment(Ray);
}
#ifdef ORACLE_TRACE
// ORACLE_EXIT_POINT | ORACLE_EXIT_NORMAL | ORACLE_NEARBY (src/scene/techniques.rs, HuQinOracle).
layout(constant_id = 10) const uint ORACLE = 0;
// The reference's own intersection code and buffers (glsl/reference/trace.glsl), in a set of
// their own: their REF_BINDING_* would meet the G-buffer's and the layers' in set 1.
#define REF_SET 2
#include "../reference/trace.glsl"

// The reference's ray epsilon at p (offset_origin's).
float oracle_eps(vec3 p) {
    return ref.proj.z * (1.0 + max(max(abs(p.x), abs(p.y)), abs(p.z)) / max(ref.proj.w, 1e-30));
}

// §2.2's lookup replaced: the exact hit X of the ray (P + t Ray, leaving the surface of
// outward normal N_out at P) against the scene, shown as the technique shows it: TEX_k's
// radiance at X's texel, in the rectangle k whose projection holds X and whose TEX_DEPTH_k
// there is nearest X's own depth (X itself where some projection sees it; where all hide it,
// the surface that hides it: the textures' limit, which no search removes). The environment
// where the ray hits nothing or no texture holds a surface at X's texel (the paper's rule
// where no rectangle is hit). OBJ_R itself is passed through: its own rectangle set does not
// hold it (§2.2.1), and the paper's P2 (or the tessellated P1) may lie inside its exact
// surface. Nothing of the search of Figs. 13, 16, 17 is used, so the result does not depend
// on its parameters.
vec3 oracle_nearby_radiance(vec3 P, vec3 Ray, vec3 N_out) {
    if (!nearby_has_set()) return environment(Ray);
    uint own = nearby_header.sets[nearby_set].z;
    vec3 o = P + N_out * (dot(Ray, N_out) >= 0.0 ? 1.0 : -1.0) * oracle_eps(P);
    vec3 X;
    bool found = false;
    // A closed OBJ_R is crossed in two hits; 8 allow for a concave one's folds.
    for (int pass = 0; pass < 8 && !found; ++pass) {
        Hit h = trace(o, Ray, 3.4e38);
        if (h.kind == 0u) return environment(Ray);
        Surface s = surface_at(o, Ray, h);
        uint object = object_of(h.kind, h.prim);
        found = object != own;
        X = s.p;
        o = offset_origin(s, Ray);
    }
    if (!found) return environment(Ray);
    uint first = nearby_header.sets[nearby_set].x;
    uint end = first + min(nearby_header.sets[nearby_set].y, MAX_NEARBY_RECTS);
    float best = 1e30;
    vec3 color = environment(Ray);
    vec3 origin = nearby_origin();
    for (uint k = first; k < end; ++k) {
        GpuNearbyRect r = nearby_rects[k];
        vec3 q = nearby_project(r, origin, X);
        if (!nearby_inside(q.xy)) continue;
        vec4 texel = nearby_texel(r, q.xy);
        if (!nearby_covered(r, texel)) continue;
        float e = abs(texel.a - q.z);
        if (e < best) {
            best = e;
            color = texel.rgb;
        }
    }
    return finite_or_zero(color);
}
#endif
layout(set = 1, binding = BINDING_GBUF_NORMAL) uniform sampler2D gbuf_normal;
layout(set = 1, binding = BINDING_GBUF_DEPTH) uniform sampler2D gbuf_depth;
// a: the object index (exact in half float up to 2048), which picks the rectangle set.
layout(set = 1, binding = BINDING_GBUF_ALBEDO) uniform sampler2D gbuf_albedo;
layout(set = 1, binding = BINDING_REFR_BACK_NORMAL) uniform sampler2D back_normal;
layout(set = 1, binding = BINDING_REFR_BACK_DEPTH) uniform sampler2D back_depth;
layout(set = 1, binding = BINDING_REFR_FRONT_NORMAL) uniform sampler2D front_normal;
layout(set = 1, binding = BINDING_REFR_FRONT_DEPTH) uniform sampler2D front_depth;
layout(location = 0) in vec2 in_uv;
layout(location = 0) out vec4 out_radiance;
layout(location = 1) out vec4 out_p2;
layout(location = 2) out vec4 out_t2;

// The camera view's layers for the exit search shared with the impostor textures
// (glsl/include/hu_qin_exit.glsl). Depths are the view-space distances along -z rather than
// the paper's [0, 1] buffer z, which with prism's reversed-Z infinite projection is far from
// linear; the back layer's coverage is the refractor's silhouette.
// Coverage from the depth layers, which the d_T search reads anyway at the same texel.
bool exit_covered(bool front, vec2 uv) {
    return front ? layer_depth_covered(front_depth, uv) : layer_depth_covered(back_depth, uv);
}
bool exit_layer(bool front, vec2 uv, out float depth) {
    float d = 0.0;
    if (on_screen(uv)) d = front ? texelFetch(front_depth, texel_of(uv), 0).r : texelFetch(back_depth, texel_of(uv), 0).r;
    // As layer_view_depth (reversed Z: near / depth).
    depth = frame.clip.x / max(d, 1e-30);
    return d > 0.0;
}
vec2 exit_project(vec3 P) {
    return project_uv(P);
}
// The depth is view_depth's, -z in view space.
vec4 exit_affine(vec3 P, float w) {
    vec4 clip = frame.view_proj * vec4(P, w);
    return vec4(clip.xy, -(frame.view * vec4(P, w)).z, clip.w);
}
vec2 exit_affine_uv(vec4 a) {
    return a.xy / a.w * 0.5 + 0.5;
}
vec3 exit_back_point(vec2 uv) {
    return world_from_depth(uv, texelFetch(back_depth, texel_of(uv), 0).r);
}
#include "hu_qin_exit.glsl"

void main() {
    ivec2 px = ivec2(gl_FragCoord.xy);
    float depth = texelFetch(gbuf_depth, px, 0).r;
    if (depth <= 0.0) discard;
    vec4 nm = texelFetch(gbuf_normal, px, 0);
    uint mat = uint(nm.w + 0.5);
    if (material_kind(mat) != MATERIAL_DIELECTRIC) discard;
    GpuMaterial m = materials[mat];
    vec3 ior = max(m.spec_a.rgb, vec3(1e-6));
    bool one_ior = DISPERSION == 0u || (ior.r == ior.g && ior.g == ior.b);
    vec3 V = camera_ray(in_uv);
    vec3 N1 = normalize(nm.xyz);
    // A camera inside the refractor sees a back face: one interface, as the baseline
    // (specular/single.frag), with N1 turned to face the camera and the same Fresnel term and
    // two lookups as the two interfaces below (R and T1 meet the nearby objects, as every ray
    // leaving OBJ_R does). A CPU device (lavapipe) runs a branch's code for every pixel,
    // lanes masked, so a path of its own would add two lookups to each.
    bool from_inside = dot(V, N1) > 0.0;
    if (from_inside) N1 = -N1;
    vec3 P1 = world_from_depth(in_uv, depth);
    float dist1 = length(P1 - frame.camera_position.xyz);
    float tol = TOLERANCE * dist1;
    float cos_i = clamp(-dot(V, N1), 0.0, 1.0);
    if (NEARBY != 0u) nearby_select_object(uint(texelFetch(gbuf_albedo, px, 0).a + 0.5));
    vec3 L_reflected = seen_from(P1, reflect(V, N1));
#ifdef ORACLE_TRACE
    if ((ORACLE & ORACLE_NEARBY) != 0u) L_reflected = oracle_nearby_radiance(P1, reflect(V, N1), N1);
#endif
    // The back layer's thickness along the view ray: the first step of a back-facing search
    // (the paper's "small positive value" would need more iterations to reach the far side).
    float d_V = max(layer_view_depth(back_depth, in_uv) - view_depth(P1), tol);

    // Exact per-channel refraction (dispersion) when the ior is RGB; one path otherwise.
    int channels = one_ior ? 1 : 3;
    vec3 L = vec3(0.0);
    for (int c = 0; c < 3; ++c) {
        int k = channels == 1 ? 0 : c;
        float eta = from_inside ? ior[k] : 1.0 / ior[k];
        float F = fresnel_dielectric(cos_i, eta);
        vec3 T1 = refract(V, N1, eta);
        // No TIR at P1.
        bool enters = dot(T1, T1) > 0.0;
        vec3 P2 = P1, T2 = vec3(0.0), N2 = vec3(0.0);
        // debug: 0 no exit (TIR at P1); 1 back-facing, 2 front-facing exit (§2.1.2); 3 and 4 the
        // same decisions with P2 outside the chosen layer's coverage (N2 from §3.3 of Wyman 2005).
        float kind = 0.0;
        float d_T = 0.0;
        if (enters && !from_inside) {
            // §2.1.2: which surface P2 lies on.
            bool front = false;
            // A small positive first step for the front-facing search (Fig. 9), 1% of the
            // eye distance: the iteration starts at P1, which lies on the front layer.
            float step_front = 0.01 * dist1;
            bool found;
            if (ASSUME_BACK_FACING == 0) {
                // Fig. 7's interval is "75 percent of the depth buffer size" (0.75 in uv units,
                // the paper's -1..1 span being 2): 8 steps resolve 0.75/256 of the image.
                front = hu_qin_exit_is_front(V, in_uv, P1, T1, 0.01 * dist1, 0.75);
                if (front) hu_qin_search_d_t(true, P1, T1, tol, step_front, d_T, found);
                else hu_qin_search_d_t(false, P1, T1, tol, d_V, d_T, found);
            } else if (!hu_qin_search_d_t(false, P1, T1, tol, d_V, d_T, found)) {
                // Section 4: P2 left the silhouette, so the exit is front-facing.
                front = true;
                hu_qin_search_d_t(true, P1, T1, tol, step_front, d_T, found);
            }
            P2 = P1 + d_T * T1;
#ifdef ORACLE_TRACE
            // The exact exit of T1: the reference's closest hit from P1, offset inside by its
            // ray epsilon, and its shading normal turned to face out along T1 (the normal
            // interaction_at refracts about, negated). No hit (an open mesh): the paper's.
            vec3 N2_exact = vec3(0.0);
            bool exact = false;
            if ((ORACLE & (ORACLE_EXIT_POINT | ORACLE_EXIT_NORMAL)) != 0u) {
                vec3 o = P1 - N1 * oracle_eps(P1);
                Hit h = trace(o, T1, 3.4e38);
                if (h.kind != 0u) {
                    Surface s = surface_at(o, T1, h);
                    exact = true;
                    N2_exact = dot(T1, s.ng) > 0.0 ? s.ns : -s.ns;
                    // §2.1.2-2.1.3 (Fig. 5's decision, Fig. 9's d_T) replaced by the exact exit;
                    // its facing seen from the eye picks §2.1.4's layer.
                    if ((ORACLE & ORACLE_EXIT_POINT) != 0u) {
                        P2 = s.p;
                        d_T = length(s.p - P1);
                        front = dot(N2_exact, P2 - frame.camera_position.xyz) < 0.0;
                    }
                }
            }
#endif
            vec2 uv2 = project_uv(P2);
            // §2.1.4: N2 from the normal layer matching the exit surface. One fetch of its
            // texel serves the coverage test and N2, as in Wyman's pass: a layer's normal is
            // zero where it holds no surface, a unit vector where it does.
            vec3 n2 = vec3(0.0);
            if (on_screen(uv2)) {
                ivec2 t2 = texel_of(uv2);
                n2 = front ? texelFetch(front_normal, t2, 0).xyz : texelFetch(back_normal, t2, 0).xyz;
            }
            bool covered = dot(n2, n2) > 0.25;
            N2 = covered ? normalize(n2) : silhouette_normal(T1);
#ifdef ORACLE_TRACE
            // §2.1.4's N2 replaced by the exact normal at T1's exit.
            if (exact && (ORACLE & ORACLE_EXIT_NORMAL) != 0u) {
                N2 = N2_exact;
                covered = true;
            }
#endif
            kind = (front ? 2.0 : 1.0) + (covered ? 0.0 : 2.0);
            // Leaving the object: the normal facing T1 is -N2 and eta = n_refractor / n_outside;
            // TIR at P2 is clamped to the critical angle as in Wyman 2005 §3.3.
            T2 = refract_clamped(T1, -N2, ior[k]);
        }
        // From inside, T1 leaves the refractor at P1. Under TIR at P1, F = 1 and the lookup
        // (along R, a direction that exists) adds nothing.
        vec3 L_T2 = seen_from(P2, from_inside ? T1 : enters ? T2 : reflect(V, N1));
#ifdef ORACLE_TRACE
        if ((ORACLE & ORACLE_NEARBY) != 0u && !from_inside) L_T2 = oracle_nearby_radiance(P2, T2, N2);
#endif
        vec3 L_t = enters ? L_T2 * exp(-m.spec_b.rgb * d_T) : vec3(0.0);
        if (channels == 1) {
            L = F * L_reflected + (1.0 - F) * L_t;
        } else {
            L[c] = F * L_reflected[c] + (1.0 - F) * L_t[c];
        }
        if (c == 0 && DEBUG != 0) {
            out_p2 = vec4(P2, kind);
            out_t2 = vec4(T2, d_T);
        }
        if (channels == 1) break;
    }
    out_radiance = vec4(finite_or_zero(L), 1.0);
}
