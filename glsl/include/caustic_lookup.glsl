// Caustic irradiance on a diffuse receiver, looked up in the caustic textures of the frame
// set: caustics mapping's atlas (Shah et al. 2007) and the photon buffer's rectangles (Hu & Qin
// 2007 §3.3). Shared by deferred shading (glsl/shading/deferred.frag) and the receivers seen
// through a water surface (glsl/refraction/water.frag), so that a floor seen through the water
// carries the same caustic as one seen directly. The includer declares the specialisation
// constants CAUSTICS, CAUSTIC_FILTER, PHOTON_RECTS and PHOTON_MODE first (deferred.frag explains them).
#ifndef PRISM_CAUSTIC_LOOKUP_GLSL
#define PRISM_CAUSTIC_LOOKUP_GLSL
#include "frame.glsl"

// Caustic irradiance (W/m^2) at p from light i: "each point of the receiver surface is
// projected into the light's view" (§III.B step 5) and the caustic map's flux per texel is
// divided by the receiver area that texel covers there: r^2 dOmega / cos for a cube texel of
// solid angle dOmega at distance r, (texel size)^2 / cos for the orthographic map, cos
// between the receiver normal n (turned towards the viewer) and the direction to the light.
// The flux of a texel fell on the receiver the light sees there (§III.B step 1): a point on
// the side facing away from the light (cos <= 0), or further from the light than that
// receiver, receives none of it. The depth test is the shadow maps' (lighting.glsl), with the
// point pushed towards the light by CAUSTIC_DEPTH_BIAS_TEXELS texel footprints.
vec3 caustic_irradiance(uint i, vec3 p, vec3 n) {
    GpuLight l = frame.lights[i];
    float layer = l.intensity.w;
    float size = float(textureSize(caustic_layers, 0).x);
    int k = int(CAUSTIC_FILTER);
    float taps = float((2 * k + 1) * (2 * k + 1));
    vec3 flux = vec3(0.0);
    if (is_point_light(l)) {
        vec3 d = p - l.position.xyz;
        float r2 = dot(d, d);
        vec3 a = abs(d);
        float m = max(a.x, max(a.y, a.z));
        if (!(m > 0.0)) return vec3(0.0);
        float r = sqrt(r2);
        float cosine = -dot(n, d) / r;
        if (!(cosine > 0.0)) return vec3(0.0);
        vec3 u = d / m;   // on the cube: the major coordinate is +-1
        float cube_layer = layer / float(SHADOW_LAYERS_PER_LIGHT);
        // A cube texel at distance r is at most r * 2 / size wide (at a face's centre).
        vec3 q = p + n * (CAUSTIC_DEPTH_BIAS_TEXELS * r * 2.0 / size);
        float receiver = textureLod(caustic_receiver_cubes, vec4(u, cube_layer), 0.0).r;
        if (length(q - l.position.xyz) > receiver) return vec3(0.0);
        vec3 e1 = a.x == m ? vec3(0, 1, 0) : vec3(1, 0, 0);
        vec3 e2 = a.z == m ? vec3(0, 1, 0) : vec3(0, 0, 1);
        for (int y = -k; y <= k; ++y) {
            for (int x = -k; x <= k; ++x) {
                vec3 t = u + (float(x) * e1 + float(y) * e2) * (2.0 / size);
                flux += textureLod(caustic_cubes, vec4(t, cube_layer), 0.0).rgb;
            }
        }
        float qq = dot(u, u);   // 1 + a^2 + b^2 of the texel's face coordinates (a, b)
        float d_omega = (2.0 / size) * (2.0 / size) / (qq * sqrt(qq));
        return flux / taps * cosine / max(d_omega * r2, 1e-30);
    }
    float cosine = -dot(n, l.position.xyz);
    if (!(cosine > 0.0)) return vec3(0.0);
    vec4 clip = l.view_proj * vec4(p, 1.0);
    vec2 uv = clip.xy * 0.5 + 0.5;
    if (any(lessThan(uv, vec2(0.0))) || any(greaterThan(uv, vec2(1.0)))) return vec3(0.0);
    // The orthographic map spans 2 * far/2 metres (GpuLight.shadow.y = 2r, the map's side).
    float texel = l.shadow.y / size;
    vec3 q = p + n * (CAUSTIC_DEPTH_BIAS_TEXELS * texel);
    float receiver = textureLod(caustic_receiver_layers, vec3(uv, layer), 0.0).r;
    if (dot(q - l.origin.xyz, l.position.xyz) > receiver) return vec3(0.0);
    for (int y = -k; y <= k; ++y) {
        for (int x = -k; x <= k; ++x) {
            flux += textureLod(caustic_layers, vec3(uv + vec2(x, y) / size, layer), 0.0).rgb;
        }
    }
    return flux / taps * cosine / (texel * texel);
}

// Photon-buffer caustics at p (Hu & Qin 2007 §3.3, Fig. 23): p, a point of object
// `object` (the G-buffer's albedo.a), is projected with the parallel projection of that
// object's rectangle RECT_i into TEX_CAUSTICS_i (0 if the object has no rectangle: it is not
// among the MAX_NEARBY_RECTS receivers). PHOTON_PHYSICAL: irradiance on the rectangle
// (W/m^2) times -n . axis, the footprint of a texel projected along the axis onto a
// receiver tilted against it; returned as irradiance. PHOTON_PAPER: the paper's intensity c,
// "blended with the object's own colour" (returned as is, multiplied by the albedo by the
// caller). The photons arrive from the specular objects at O_R, on the side of the receiver
// that faces O_R (the rectangle's axis points from O_R to the object, §2.2.1): the side n
// turned away from O_R receives none (a floor seen from below).
vec3 photon_caustic(vec3 p, vec3 n, uint object) {
    for (uint i = 0u; i < PHOTON_RECTS; ++i) {
        GpuPhotonRect r = photon_rects[i];
        if (r.object.x != object) continue;
        if (!(dot(n, r.axis.xyz) < 0.0)) return vec3(0.0);
        vec2 uv = rect_uv(r, p);
        if (any(lessThan(uv, vec2(0.0))) || any(greaterThan(uv, vec2(1.0)))) return vec3(0.0);
        vec3 c = textureLod(photon_caustics, vec3(uv, float(i)), 0.0).rgb;
        if (PHOTON_MODE == PHOTON_PAPER) return c;
        return c * -dot(n, r.axis.xyz);
    }
    return vec3(0.0);
}

// The caustic radiance a Lambertian receiver of albedo `albedo` at p (unit normal n, facing
// the viewer; object index `object`) adds to its shading, from whichever caustic textures
// are rendered.
vec3 caustic_radiance(vec3 p, vec3 n, uint object, vec3 albedo) {
    vec3 radiance = vec3(0.0);
    if (CAUSTICS != 0u) {
        // Caustics mapping (Shah et al. 2007): the caustic map's irradiance, Lambertian.
        vec3 caustic = vec3(0.0);
        for (uint i = 0u; i < light_count(); ++i) caustic += caustic_irradiance(i, p, n);
        radiance += albedo / PI * caustic;
    }
    if (PHOTON_RECTS != 0u) {
        vec3 c = photon_caustic(p, n, object);
        radiance += PHOTON_MODE == PHOTON_PAPER ? albedo * c : albedo / PI * c;
    }
    return radiance;
}
#endif
