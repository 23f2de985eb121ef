#version 450
// Exact ray tracing of the specular objects, or of the whole frame of a volume scene
// (src/technique/raytrace.rs): one ray through each covered pixel's centre (every pixel's,
// MODE = RAYTRACE_MODE_FRAME) follows the exact specular chain with deterministic splitting. At a
// dielectric both the reflected and the refracted branch are followed, weighted by exact
// Fresnel (per channel when the ior is), until a branch escapes to the environment, reaches a
// diffuse surface (which gathers what the reference's camera paths gather there,
// glsl/reference/paths.glsl, and the caustic from this frame's photons), has made max_depth
// interactions, or carries less than the cutoff. The scene, the intersection, the materials
// and the photon grid are the reference's own code (glsl/reference/trace.glsl,
// photon_grid.glsl), their buffers bound in set 1.
#include "frame.glsl"
#include "environment.glsl"
#define REF_SET 1
#include "../reference/paths.glsl"
#include "caustic.glsl"

layout(constant_id = 0) const uint MODE = SPECULAR_MODE_REFRACTION;
// A branch makes at most ref.counts.w specular interactions (the reference's max_depth, at
// most RAYTRACE_MAX_DEPTH) and is dropped when its largest throughput channel falls below
// ref.grid.w (the cutoff). Uniforms rather than specialisation constants: one pipeline per
// mode, whatever the parameters. The photons of this frame (ref.photon.x of them, none: no
// caustics) were traced by the reference's photon kernel just before this pass; ref.grid.z is
// the gathering radius in pixel footprints, at most ref.grid.y.
// RT1 of the G-buffer: a = object index. Its binding and the depth's are free in set 1:
// they fall on REF_BINDING_MATERIALS and _ENVIRONMENT, which come from the frame set here.
layout(set = 1, binding = BINDING_GBUF_ALBEDO) uniform sampler2D gbuf_albedo;
layout(set = 1, binding = BINDING_GBUF_DEPTH) uniform sampler2D gbuf_depth;
layout(location = 0) in vec2 in_uv;
layout(location = 0) out vec4 out_radiance;

struct Branch {
    vec3 o;
    vec3 d;
    vec3 beta;    // throughput, (n_i/n_t)^2 radiance scaling included
    uint depth;   // rays traced before this one (the reference camera path's `bounce`)
    float travelled;   // from the camera along the chain, to o
};

float largest(vec3 v) { return max(v.x, max(v.y, v.z)); }

// Radiance along the ray (o, d) with initial throughput beta. Depth first: each branch goes on
// along its reflection and leaves its transmission on the stack; the stack holds at most one
// branch per depth, in increasing depth, so max_depth entries suffice.
vec3 trace_split(vec3 o, vec3 d, vec3 beta, int channel, inout uint rng) {
    uint max_depth = min(ref.counts.w, RAYTRACE_MAX_DEPTH);
    float cutoff = ref.grid.w;
    Branch stack[RAYTRACE_MAX_DEPTH];
    uint sp = 0u;
    Branch b = Branch(o, d, beta, 0u, 0.0);
    vec3 L = vec3(0.0);
    while (true) {
        for (; b.depth <= max_depth; ++b.depth) {
            Hit h = trace(b.o, b.d, 3.4e38);
            float tv;
            if (region_entry(b.o, b.d, h.kind == 0u ? 3.4e38 : h.t, tv)) {
                if (!volume_cross(b.o, b.d, tv, b.beta, L, channel, rng)) break;
                continue;
            }
            if (h.kind == 0u) {
                L += b.beta * environment(b.d);
                break;
            }
            Surface s = surface_at(b.o, b.d, h);
            // Segments through a graded-index volume are not counted (as camera.comp).
            b.travelled += h.t;
            if (kind_of(materials[s.material]) == MATERIAL_DIFFUSE) {
                vec3 n = gather_diffuse(s, b.d, b.beta, channel, rng, L);
                if (ref.photon.x > 0u) L += b.beta * caustic_at(s, b.d, n, b.travelled);
                break;
            }
            Interaction x;
            if (!interaction_at(s, b.d, h.t, channel, true, x)) break;
            vec3 weight = b.beta * x.weight;
            if (x.transmits) {
                vec3 t_beta = weight * (1.0 - x.F) * x.scale;
                if (b.depth < max_depth && sp < max_depth && largest(t_beta) >= cutoff) {
                    stack[sp++] = Branch(offset_origin(s, x.refracted), x.refracted, t_beta, b.depth + 1u, b.travelled);
                }
                weight *= x.F;
            }
            if (largest(weight) < cutoff) break;
            b.beta = weight;
            b.d = x.reflected;
            b.o = offset_origin(s, x.reflected);
        }
        if (sp == 0u) break;
        b = stack[--sp];
    }
    return L;
}

void main() {
    ivec2 px = ivec2(gl_FragCoord.xy);
    // The whole frame (render.volume = "raytrace"): every pixel, its first surface or the
    // volume found by the trace itself, not by the G-buffer, which does not cover a volume.
    if (MODE != RAYTRACE_MODE_FRAME) {
        if (texelFetch(gbuf_depth, px, 0).r <= 0.0) discard;
        uint object = uint(texelFetch(gbuf_albedo, px, 0).a + 0.5);
        uint kind = material_kind(object_material(object));
        bool dielectric = kind == MATERIAL_DIELECTRIC;
        bool metal = kind == MATERIAL_MIRROR || kind == MATERIAL_CONDUCTOR;
        if ((MODE == SPECULAR_MODE_REFRACTION && !dielectric) || (MODE == SPECULAR_MODE_REFLECTION && !metal)) discard;
    }

    // The diffuse vertices' environment sample: the same per pixel in every frame, so that
    // the image is a function of the scene.
    uint rng = rng_init(uint(px.y) * uint(frame.viewport.x) + uint(px.x), 0u, 0u);
    vec3 o = frame.camera_position.xyz, d = camera_ray(in_uv);
    vec3 L;
    if ((ref.photon.w & REF_FLAG_DISPERSION) != 0u) {
        // One branch tree per wavelength channel, each carrying its own channel.
        for (int c = 0; c < 3; ++c) {
            vec3 beta = vec3(0.0);
            beta[c] = 1.0;
            L[c] = trace_split(o, d, beta, c, rng)[c];
        }
    } else {
        L = trace_split(o, d, vec3(1.0), -1, rng);
    }
    out_radiance = vec4(finite_or_zero(L), 1.0);
}
