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
// glsl/eikonal/nearby_impostor.frag shades diffuse objects with the
// eikonal light simulation's irradiance (eikonal_receiver, declared before this include).
#ifndef NEARBY_EIKONAL_LIGHT
#define NEARBY_EIKONAL_LIGHT 0
#endif
#if NEARBY_RECURSIVE
// The lookup of the level below: the same correction as refraction_hu_qin (constants 0..2).
layout(constant_id = 0) const uint NEARBY_ITERATIONS = 3;
layout(constant_id = 1) const float NEARBY_TOLERANCE = 1e-3;
layout(constant_id = 2) const uint NEARBY_SEEDS = 8;
// render.hu_qin.recursive_lookup (glsl/include/nearby.glsl); id 12, past the eikonal
// impostor shader's constants 6..11.
layout(constant_id = 12) const uint NEARBY_LOOKUP = NEARBY_LOOKUP_PAPER;
#include "nearby.glsl"
#endif
// A dielectric's exit (render.hu_qin.recursive_exit): 2 "full", §2.1's whole method in the
// rectangle's projection (Fig. 7's dividing pixel, Fig. 5's front/back test, Fig. 9's search
// on the front or back layer); 1 "back_facing", §4's acceleration (the exit assumed
// back-facing: Fig. 9 on the back layer only); 0 "bounding_sphere".
layout(constant_id = 3) const uint NEARBY_EXIT = 2;
// Fig. 7's halvings and Fig. 9's steps (render.hu_qin.search_steps, max_iterations).
layout(constant_id = 4) const uint SEARCH_STEPS = 8;
layout(constant_id = 5) const uint MAX_ITERATIONS = 32;
// Fig. 9's own step and stopping rule in the impostor textures (glsl/include/hu_qin_exit.glsl).
const uint D_T_STEP = D_T_STEP_PAPER;
const uint D_T_BRACKET = 0u;
// The dielectrics' nearest back and front faces (BACK_PASS of src/technique/refraction/nearby_impostors.rs),
// layer = the rectangle's: xyz outward normal (0: none), w axial depth.
layout(set = 1, binding = BINDING_NEARBY_BACK) uniform sampler2DArray nearby_back;
layout(set = 1, binding = BINDING_NEARBY_FRONT) uniform sampler2DArray nearby_front;
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

// The rectangle's parallel projection as the view of §2.1's exit search
// (glsl/include/hu_qin_exit.glsl): uv of TEX_k, depths are axial distances from O_R (linear).
vec2 exit_project(vec3 P) {
    vec4 clip = pc.view_proj * vec4(P, 1.0);
    return clip.xy * 0.5 + 0.5;
}
float exit_point_depth(vec3 P) {
    return dot(P - pc.origin.xyz, pc.axis.xyz);
}
vec4 exit_affine(vec3 P, float w) {
    vec4 clip = pc.view_proj * vec4(P, w);
    return vec4(clip.xy, dot(P - w * pc.origin.xyz, pc.axis.xyz), w);
}
vec2 exit_affine_uv(vec4 a) {
    return a.xy * 0.5 + 0.5;
}
// OBJ_k's front (true) or back layer texel at uv; zero outside the texture.
vec4 exit_texel(bool front, vec2 uv) {
    if (any(lessThan(uv, vec2(0.0))) || any(greaterThan(uv, vec2(1.0)))) return vec4(0.0);
    vec3 at = vec3(uv, float(pc.material.y));
    return front ? textureLod(nearby_front, at, 0.0) : textureLod(nearby_back, at, 0.0);
}
bool exit_covered(bool front, vec2 uv) {
    vec4 t = exit_texel(front, uv);
    return dot(t.xyz, t.xyz) > 0.25;
}
float exit_layer_depth(bool front, vec2 uv) {
    return exit_texel(front, uv).w;
}
bool exit_layer(bool front, vec2 uv, out float depth) {
    vec4 t = exit_texel(front, uv);
    depth = t.w;
    return dot(t.xyz, t.xyz) > 0.25;
}
// The back layer's point at uv: the projection's rays are parallel to the axis, so any point
// that projects to uv, moved along the axis to the layer's axial depth.
vec3 exit_back_point(vec2 uv) {
    vec4 q = inverse(pc.view_proj) * vec4(uv * 2.0 - 1.0, 0.0, 1.0);
    vec3 Q = q.xyz / q.w;
    return Q + (exit_layer_depth(false, uv) - exit_point_depth(Q)) * pc.axis.xyz;
}
#include "hu_qin_exit.glsl"

// §2.1.2-2.1.4 in the parallel projection: d along T1 from P1 to OBJ_k's exit and the exit's
// normal N2. The eye ray is V = +axis everywhere. With NEARBY_EXIT 2, Fig. 7's dividing pixel
// (searched over the whole texture: OBJ_k lies within its bounding sphere, whose diameter is
// the texture's side, so span 1 in uv) and Fig. 5's test pick the front or back layer; with 1
// the exit is assumed back-facing (§4). Fig. 9's first step: the back layer's thickness along
// V at P1 (d_V, as the main pass), or 1% of d_k on the front layer (the main pass's 1% of the
// eye distance; the ortho view has no eye distance). False when no covered point was found:
// the caller falls back to the bounding sphere.
bool exit_on_layers(vec3 P1, vec3 T1, out float d, out vec3 N2) {
    d = 0.0;
    N2 = vec3(0.0);
    vec2 p1 = exit_project(P1);
    if (!exit_covered(false, p1)) return false;
    float tol = 1e-4 * pc.sphere.w;
    bool front = NEARBY_EXIT == 2u && hu_qin_exit_is_front(pc.axis.xyz, p1, P1, T1, 0.01 * pc.sphere.w, 1.0);
    bool found;
    if (front) {
        hu_qin_search_d_t(true, P1, T1, tol, 0.01 * pc.sphere.w, d, found);
    } else {
        float d_V = max(exit_layer_depth(false, p1) - exit_point_depth(P1), tol);
        hu_qin_search_d_t(false, P1, T1, tol, d_V, d, found);
    }
    if (!found) return false;
    vec4 t = exit_texel(front, exit_project(P1 + d * T1));
    if (!(dot(t.xyz, t.xyz) > 0.25)) return false;
    N2 = normalize(t.xyz);
    return true;
}

// A dielectric OBJ_k as the main pass shows OBJ_R (glsl/refraction/hu_qin.frag), with the
// projection's eye ray V = +axis: the Fresnel-weighted reflection at P1 and refraction through
// two interfaces. P1 and N1 are this fragment (the nearest surface in the parallel
// projection); the exit P2 and N2 come from §2.1's search on OBJ_k's front and back faces
// (exit_on_layers), or - with render.hu_qin.recursive_exit = "bounding_sphere", and where
// that search finds nothing - from OBJ_k's bounding sphere (O_k, d_k), the rectangle's own
// centre and half-size: T1 leaves where it leaves that sphere, with the sphere's normal. The
// sphere is exact for a ball (up to its tessellation); for other shapes its exit lies further
// out than the true one.
vec3 dielectric_texel(vec3 P1, vec3 N1, GpuMaterial m) {
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
            float d;
            vec3 N2;
            if (NEARBY_EXIT == 0u || !exit_on_layers(P1, T1, d, N2)) {
                // Far intersection of P1 + d T1 with the sphere: P1 lies inside it (every
                // vertex is within d_k of O_k, and the faces between them too): root >= 0.
                vec3 o = P1 - pc.sphere.xyz;
                float b = dot(o, T1);
                d = max(-b + sqrt(max(b * b - (dot(o, o) - pc.sphere.w * pc.sphere.w), 0.0)), 0.0);
                N2 = P1 + d * T1 - pc.sphere.xyz;
                float len = length(N2);
                N2 = len > 1e-20 ? N2 / len : T1;
            }
            vec3 P2 = P1 + d * T1;
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
#if NEARBY_EIKONAL_LIGHT
        vec3 lo = vec3(LIGHT_MIN_X, LIGHT_MIN_Y, LIGHT_MIN_Z), hi = vec3(LIGHT_MAX_X, LIGHT_MAX_Y, LIGHT_MAX_Z);
        radiance = eikonal_receiver(in_position, n, albedo_at(materials[mat], in_checker_uv), lo, hi);
#else
        radiance = diffuse_radiance(in_position, n, albedo_at(materials[mat], in_checker_uv));
#endif
    } else if (kind == MATERIAL_MIRROR || kind == MATERIAL_CONDUCTOR) {
        // The parallel projection's eye ray is +axis everywhere.
        vec3 R = reflect(pc.axis.xyz, n);
        float cos_i = clamp(-dot(pc.axis.xyz, n), 0.0, 1.0);
        GpuMaterial m = materials[mat];
        vec3 F = kind == MATERIAL_MIRROR ? m.spec_a.rgb : fresnel_conductor(cos_i, m.spec_a.rgb, m.spec_b.rgb);
        radiance = F * seen_from(in_position, R);
    } else if (kind == MATERIAL_DIELECTRIC) {
        radiance = dielectric_texel(in_position, n, materials[mat]);
    }
    out_texel = vec4(finite_or_zero(radiance), dot(in_position - pc.origin.xyz, pc.axis.xyz));
}
