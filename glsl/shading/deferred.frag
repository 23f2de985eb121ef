#version 450
// Deferred shading of diffuse surfaces (direct light with shadow maps, plus environment
// irradiance) and the environment background. Specular surfaces are left black here and
// filled by their technique's pass.
#include "frame.glsl"
#include "environment.glsl"
#include "lighting.glsl"
layout(set = 1, binding = BINDING_GBUF_NORMAL) uniform sampler2D gbuf_normal;
layout(set = 1, binding = BINDING_GBUF_ALBEDO) uniform sampler2D gbuf_albedo;
layout(set = 1, binding = BINDING_GBUF_DEPTH) uniform sampler2D gbuf_depth;
// Caustics mapping (Shah et al. 2007, §III.B step 5): 1 when a caustic map is rendered;
// the radius in texels of the optional box low-pass filter of the map (§III.F).
layout(constant_id = 0) const uint CAUSTICS = 0;
layout(constant_id = 1) const uint CAUSTIC_FILTER = 0;
// Photon-buffer caustics (Hu & Qin 2007 §3.3): the number of receiver rectangles (0: off)
// and PHOTON_PHYSICAL or PHOTON_PAPER.
layout(constant_id = 2) const uint PHOTON_RECTS = 0;
layout(constant_id = 3) const uint PHOTON_MODE = 0;
// 0 when the scene has no diffuse object: the pass then only draws the environment behind
// the specular objects. A specialisation constant rather than the material test alone: a
// CPU device (lavapipe) runs both sides of a branch with lanes masked, so every background
// pixel paid for the whole diffuse path (irradiance, every light's shadow taps, caustic
// lookups): 18 ms against 2 ms for the tone map on sphere_env at 512^2 (docs/BENCHMARKS.md).
layout(constant_id = 4) const uint DIFFUSE = 1;
layout(location = 0) in vec2 in_uv;
layout(location = 0) out vec4 out_radiance;

#include "caustic_lookup.glsl"

void main() {
    ivec2 px = ivec2(gl_FragCoord.xy);
    float depth = texelFetch(gbuf_depth, px, 0).r;
    vec3 ray = camera_ray(in_uv);
    if (depth <= 0.0) {
        // Reversed Z: depth 0 is infinity, nothing was drawn: the environment is seen.
        out_radiance = vec4(finite_or_zero(environment(ray)), 1.0);
        return;
    }
    vec4 nm = texelFetch(gbuf_normal, px, 0);
    uint mat = uint(nm.w + 0.5);
    if (DIFFUSE == 0u || material_kind(mat) != MATERIAL_DIFFUSE) {
        out_radiance = vec4(0.0, 0.0, 0.0, 1.0);
        return;
    }
    vec3 p = world_from_depth(in_uv, depth);
    vec3 n = normalize(nm.xyz);
    // Two-sided diffuse: shade the side the camera sees.
    if (dot(n, ray) > 0.0) n = -n;
    vec4 albedo_object = texelFetch(gbuf_albedo, px, 0);
    vec3 albedo = albedo_object.rgb;
    vec3 radiance = diffuse_radiance(p, n, albedo);
    radiance += caustic_radiance(p, n, uint(albedo_object.a + 0.5), albedo);
    out_radiance = vec4(finite_or_zero(radiance), 1.0);
}
