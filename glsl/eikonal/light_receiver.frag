#version 450
// Diffuse receivers inside the irradiance volume receive the simulated light (Ihrke et al.
// 2007, Fig. 1 left: the caustic on the table; Eq. 7 with a Lambertian BRDF, one incoming
// ray per voxel). The irradiance volume covers the volume's box and `light_below` metres
// under it (src/passes/eikonal_light.rs), so a floor just under the volume lies inside.
// There the simulated light replaces the unoccluded direct terms of the lights (all of them
// are simulated): the wavefronts carry both the light that missed the volume (I / r^2, the
// same as the direct term) and the refracted, focused light. The environment and the
// shadow maps of meshes stay as deferred_shading computes them.
#include "frame.glsl"
#include "environment.glsl"
#include "lighting.glsl"
layout(set = 1, binding = BINDING_GBUF_NORMAL) uniform sampler2D gbuf_normal;
layout(set = 1, binding = BINDING_GBUF_ALBEDO) uniform sampler2D gbuf_albedo;
layout(set = 1, binding = BINDING_GBUF_DEPTH) uniform sampler2D gbuf_depth;
#include "scatter.glsl"
layout(constant_id = 0) const float LIGHT_MIN_X = 0.0;
layout(constant_id = 1) const float LIGHT_MIN_Y = 0.0;
layout(constant_id = 2) const float LIGHT_MIN_Z = 0.0;
layout(constant_id = 3) const float LIGHT_MAX_X = 1.0;
layout(constant_id = 4) const float LIGHT_MAX_Y = 1.0;
layout(constant_id = 5) const float LIGHT_MAX_Z = 1.0;
layout(location = 0) in vec2 in_uv;
layout(location = 0) out vec4 out_radiance;

void main() {
    ivec2 px = ivec2(gl_FragCoord.xy);
    float depth = texelFetch(gbuf_depth, px, 0).r;
    if (depth <= 0.0) discard;
    vec4 nm = texelFetch(gbuf_normal, px, 0);
    if (material_kind(uint(nm.w + 0.5)) != MATERIAL_DIFFUSE) discard;
    vec3 p = world_from_depth(in_uv, depth);
    vec3 lo = vec3(LIGHT_MIN_X, LIGHT_MIN_Y, LIGHT_MIN_Z), hi = vec3(LIGHT_MAX_X, LIGHT_MAX_Y, LIGHT_MAX_Z);
    if (any(lessThan(p, lo)) || any(greaterThanEqual(p, hi)) || frame.info.x == 0u) discard;
    vec3 n = normalize(nm.xyz);
    if (dot(n, camera_ray(in_uv)) > 0.0) n = -n;
    vec3 albedo = texelFetch(gbuf_albedo, px, 0).rgb;
    // Every light of the scene is simulated (issue 7), so the simulated irradiance replaces
    // all their direct terms: L = albedo / pi (E_environment + sum_j cos(theta_j) dE_j),
    // Eq. 7 with a Lambertian BRDF. The simulation knows only the volume; the shadow maps
    // of the meshes still darken it, by the unshadowed fraction of the lights' direct
    // irradiance here (exact with one light, a weighted mean of the lights' visibilities
    // with several).
    vec3 direct = vec3(0.0);
    vec3 direct_visible = vec3(0.0);
    for (uint i = 0u; i < frame.info.x; ++i) {
        Light l = frame.lights[i];
        vec3 wi, e;
        if (uint(l.position.w + 0.5) == LIGHT_POINT) {
            vec3 d = l.position.xyz - p;
            float r2 = max(dot(d, d), 1e-30);
            wi = d * inversesqrt(r2);
            e = l.intensity.rgb / r2;
        } else {
            wi = -l.position.xyz;
            e = l.intensity.rgb;
        }
        float cosine = dot(n, wi);
        if (cosine <= 0.0) continue;
        direct += e * cosine;
        direct_visible += e * cosine * visibility(i, p, n);
    }
    float total = direct.r + direct.g + direct.b;
    float visible = total > 0.0 ? (direct_visible.r + direct_visible.g + direct_visible.b) / total : 1.0;
    vec3 sim, mean_dir;
    vec3 simulated = light_at(p, lo, hi, sim, mean_dir) ? sim * max(dot(n, -mean_dir), 0.0) * visible : vec3(0.0);
    vec3 radiance = albedo / PI * (environment_irradiance(n) + simulated);
    out_radiance = vec4(finite_or_zero(max(radiance, vec3(0.0))), 1.0);
}
