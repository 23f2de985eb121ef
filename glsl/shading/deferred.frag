#version 450
// Deferred shading of diffuse surfaces (direct light with shadow maps, plus environment
// irradiance) and the environment background. Specular surfaces are left black here and
// filled by their technique's pass.
#include "frame.glsl"
#include "environment.glsl"
layout(set = 1, binding = BINDING_GBUF_NORMAL) uniform sampler2D gbuf_normal;
layout(set = 1, binding = BINDING_GBUF_ALBEDO) uniform sampler2D gbuf_albedo;
layout(set = 1, binding = BINDING_GBUF_DEPTH) uniform sampler2D gbuf_depth;
layout(location = 0) in vec2 in_uv;
layout(location = 0) out vec4 out_radiance;

// 1 if p is lit by light i, 0 if in shadow. The lookup point is pushed along the normal by
// a bias proportional to the distance (one shadow texel subtends distance/resolution).
float visibility(uint i, vec3 p, vec3 n) {
    Light l = frame.lights[i];
    float layer = l.intensity.w;
    if (uint(l.position.w + 0.5) == LIGHT_POINT) {
        vec3 d = p - l.position.xyz;
        float dist = length(d);
        vec3 q = p + n * (l.shadow.z * dist);
        vec3 dq = q - l.position.xyz;
        float stored = textureLod(shadow_cubes, vec4(dq, layer / float(SHADOW_LAYERS_PER_LIGHT)), 0.0).r;
        return length(dq) <= stored ? 1.0 : 0.0;
    } else {
        vec3 q = p + n * l.shadow.z;
        vec4 clip = l.view_proj * vec4(q, 1.0);
        vec2 uv = clip.xy * 0.5 + 0.5;
        if (any(lessThan(uv, vec2(0.0))) || any(greaterThan(uv, vec2(1.0)))) return 1.0;
        float stored = textureLod(shadow_layers, vec3(uv, layer), 0.0).r;
        return dot(q - l.origin.xyz, l.position.xyz) <= stored ? 1.0 : 0.0;
    }
}

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
    if (material_kind(mat) != MATERIAL_DIFFUSE) {
        out_radiance = vec4(0.0, 0.0, 0.0, 1.0);
        return;
    }
    vec3 p = world_from_depth(in_uv, depth);
    vec3 n = normalize(nm.xyz);
    // Two-sided diffuse: shade the side the camera sees.
    if (dot(n, ray) > 0.0) n = -n;
    vec3 albedo = texelFetch(gbuf_albedo, px, 0).rgb;
    vec3 irradiance = environment_irradiance(n);
    for (uint i = 0u; i < frame.info.x; ++i) {
        Light l = frame.lights[i];
        vec3 wi;
        vec3 e;
        if (uint(l.position.w + 0.5) == LIGHT_POINT) {
            vec3 d = l.position.xyz - p;
            float r2 = max(dot(d, d), 1e-30);
            wi = d * inversesqrt(r2);
            e = l.intensity.rgb / r2;          // E = I cos / r^2
        } else {
            wi = -l.position.xyz;
            e = l.intensity.rgb;               // irradiance on a surface facing the light
        }
        float cosine = dot(n, wi);
        if (cosine <= 0.0) continue;
        irradiance += e * cosine * visibility(i, p, n);
    }
    // Lambertian: L = albedo / pi * E.
    out_radiance = vec4(finite_or_zero(albedo / PI * irradiance), 1.0);
}
