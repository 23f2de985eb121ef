#version 450
// The classic single-interface baseline: one reflection and one refraction of the view
// ray at the first surface, each looked up in the environment map and weighted by exact
// Fresnel. This is the "1-sided refraction" column of Wyman 2005 (Table 1) and Hu & Qin 2007,
// prism's cost baseline for every refraction technique.
#include "frame.glsl"
#include "environment.glsl"
#include "fresnel.glsl"
layout(constant_id = 0) const uint MODE = SPECULAR_MODE_REFRACTION;
// 1 when some dielectric of the scene has a different ior per channel (dispersion), the
// only case that needs a refracted lookup per channel. A specialisation constant, not only a
// test of the material: a CPU device (lavapipe) runs both sides of a branch with lanes
// masked, so the code for three lookups must not be in the shader when one suffices.
layout(constant_id = 1) const uint DISPERSION = 1;
layout(set = 1, binding = BINDING_GBUF_NORMAL) uniform sampler2D gbuf_normal;
layout(set = 1, binding = BINDING_GBUF_DEPTH) uniform sampler2D gbuf_depth;
layout(location = 0) in vec2 in_uv;
layout(location = 0) out vec4 out_radiance;

void main() {
    ivec2 px = ivec2(gl_FragCoord.xy);
    float depth = texelFetch(gbuf_depth, px, 0).r;
    if (depth <= 0.0) discard;
    vec4 nm = texelFetch(gbuf_normal, px, 0);
    uint mat = uint(nm.w + 0.5);
    uint kind = material_kind(mat);
    bool dielectric = kind == MATERIAL_DIELECTRIC;
    bool metal = kind == MATERIAL_MIRROR || kind == MATERIAL_CONDUCTOR;
    // After this, every pixel left is of the mode's materials.
    if ((MODE == SPECULAR_MODE_REFRACTION && !dielectric) || (MODE == SPECULAR_MODE_REFLECTION && !metal)) discard;

    GpuMaterial m = materials[mat];
    vec3 I = camera_ray(in_uv);
    vec3 n = normalize(nm.xyz);
    bool inside = dot(I, n) > 0.0;     // the camera sees a back face: it is inside the object
    if (inside) n = -n;
    float cos_i = clamp(-dot(I, n), 0.0, 1.0);
    vec3 R = reflect(I, n);
    vec3 L_reflected = environment(R);
    vec3 L;
    if (MODE == SPECULAR_MODE_REFLECTION) {
        vec3 F = kind == MATERIAL_MIRROR ? m.spec_a.rgb : fresnel_conductor(cos_i, m.spec_a.rgb, m.spec_b.rgb);
        L = F * L_reflected;
    } else {
        // eta = n_i / n_t per channel.
        vec3 ior = max(m.spec_a.rgb, vec3(1e-6));
        vec3 eta = inside ? ior : 1.0 / ior;
        if (DISPERSION == 0u || (ior.r == ior.g && ior.g == ior.b)) {
            // A scalar ior: one Fresnel term, one refract() and one environment lookup for
            // all three channels, the one lookup of the papers' 1-sided baseline (Wyman 2005,
            // Table 1). Anything more would inflate the cost every technique is divided by.
            float F = fresnel_dielectric(cos_i, eta.x);
            vec3 T = refract(I, n, eta.x);
            // refract() returns 0 under total internal reflection, where F = 1.
            vec3 L_t = dot(T, T) > 0.0 ? environment(T) : vec3(0.0);
            L = F * L_reflected + (1.0 - F) * L_t;
        } else {
            // Dispersion: each channel refracts by its own ior and needs its own lookup.
            for (int c = 0; c < 3; ++c) {
                float F = fresnel_dielectric(cos_i, eta[c]);
                vec3 T = refract(I, n, eta[c]);
                vec3 L_t = dot(T, T) > 0.0 ? environment(T) : vec3(0.0);
                L[c] = F * L_reflected[c] + (1.0 - F) * L_t[c];
            }
        }
    }
    out_radiance = vec4(finite_or_zero(L), 1.0);
}
