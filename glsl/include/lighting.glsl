// Diffuse lighting shared by deferred shading (glsl/shading/deferred.frag) and the distance
// impostors (glsl/impostor/): direct light from every light with its shadow map, plus the
// environment's SH irradiance. One function, so that an impostor's radiance is exactly the
// deferred result the camera would see at the same point (Szirmay-Kalos et al. 2005, §3:
// "the computation of distance impostors is very similar to that of classical environment
// maps").
#ifndef PRISM_LIGHTING_GLSL
#define PRISM_LIGHTING_GLSL
#include "frame.glsl"
#include "environment.glsl"

// 1 if p is lit by light i, 0 if in shadow. The lookup point is pushed along the normal by
// a bias proportional to the distance (one shadow texel subtends distance/resolution).
float visibility(uint i, vec3 p, vec3 n) {
    GpuLight l = frame.lights[i];
    float layer = l.intensity.w;
    if (is_point_light(l)) {
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

// Irradiance at p (unit normal n, facing the viewer): `ambient` (the environment's) plus every
// light's, with its shadow map.
vec3 lit_irradiance(vec3 p, vec3 n, vec3 ambient) {
    vec3 irradiance = ambient;
    for (uint i = 0u; i < light_count(); ++i) {
        GpuLight l = frame.lights[i];
        vec3 wi;
        vec3 e;
        if (is_point_light(l)) {
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
    return irradiance;
}

// Outgoing radiance of a Lambertian surface at p with unit normal n (already turned towards
// the viewer: surfaces are two-sided) and the given albedo: L = albedo / pi * E.
vec3 diffuse_radiance(vec3 p, vec3 n, vec3 albedo) {
    return finite_or_zero(albedo / PI * lit_irradiance(p, n, environment_irradiance(n)));
}
#endif
