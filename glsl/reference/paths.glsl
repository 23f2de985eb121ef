// What a camera path gathers at its diffuse vertex, shared by the reference's camera paths
// (camera.comp) and the raytrace technique (glsl/raytrace/raytrace.frag): every light path
// with exactly one diffuse vertex (SCENES.md, "Light transport measured"), less the caustics
// that the reference's photons add (gather.comp).
#ifndef PRISM_REFERENCE_PATHS_GLSL
#define PRISM_REFERENCE_PATHS_GLSL
#include "volume.glsl"

// Environment radiance reaching a diffuse point along d through specular interactions only.
vec3 environment_through_specular(vec3 o, vec3 d, int channel, inout uint rng) {
    vec3 beta = vec3(1.0);
    for (uint bounce = 0u; bounce <= ref.counts.w; ++bounce) {
        Hit h = trace(o, d, 3.4e38);
        float tv;
        if (region_entry(o, d, h.kind == 0u ? 3.4e38 : h.t, tv)) {
            // Emission in the volume is counted on camera paths only.
            vec3 unused = vec3(0.0);
            if (!volume_cross(o, d, tv, beta, unused, channel, rng)) return vec3(0.0);
            continue;
        }
        if (h.kind == 0u) return beta * environment(d);
        Surface s = surface_at(o, d, h);
        if (kind_of(materials[s.material]) == MATERIAL_DIFFUSE) return vec3(0.0);   // a second diffuse vertex
        if (!specular_step(s, o, d, beta, h.t, channel, rand(rng), true)) return vec3(0.0);
    }
    return vec3(0.0);
}

// The diffuse vertex s of a path that arrived along d with throughput beta adds to L
// (1) direct light from point and directional lights with exact shadow rays, and
// (2) environment light arriving through any specular chain (one cosine-weighted sample).
// Returns the shading normal facing the side the path arrived from.
vec3 gather_diffuse(Surface s, vec3 d, vec3 beta, int channel, inout uint rng, inout vec3 L) {
    GpuMaterial m = materials[s.material];
    vec3 n = dot(d, s.ns) < 0.0 ? s.ns : -s.ns;
    vec3 ng = dot(d, s.ng) < 0.0 ? s.ng : -s.ng;
    vec3 albedo = albedo_at(m, s.st);
    vec3 brdf = albedo / PI;
    for (uint i = 0u; i < ref.dims.z; ++i) {
        RefLight l = ref.lights[i];
        vec3 wi;
        vec3 E;
        float dist;
        if (uint(l.position.w + 0.5) == LIGHT_POINT) {
            vec3 to = l.position.xyz - s.p;
            dist = length(to);
            wi = to / dist;
            E = l.intensity.rgb / (dist * dist);
        } else {
            wi = -l.position.xyz;
            dist = 3.4e38;
            E = l.intensity.rgb;
        }
        float cosine = dot(n, wi);
        if (cosine <= 0.0 || dot(ng, wi) <= 0.0) continue;
        vec3 origin = offset_origin(s, wi);
        float t_max = dist < 3.0e38 ? length(l.position.xyz - origin) * (1.0 - 1e-6) : dist;
        // Light through a refractive volume bends: no straight shadow ray reaches the
        // light through it. That light arrives by the photons, which cross the volume
        // (photons.comp), like the light behind a glass object.
        float t_volume;
        if (region_entry(origin, wi, t_max, t_volume)) continue;
        if (!occluded(origin, wi, t_max)) L += beta * brdf * E * cosine;
    }
    // Cosine-weighted sample: pdf cos/pi cancels the BRDF's 1/pi and the cosine.
    vec3 wi = cosine_sample(n, rng);
    if (dot(wi, ng) > 0.0) L += beta * albedo * environment_through_specular(offset_origin(s, wi), wi, channel, rng);
    return n;
}
#endif
