// Single scattering of the simulated light along a curved view ray (Ihrke et al. 2007,
// Eqs. 2, 3 and 6, sections 4.1 and 5.3): with one incoming ray per voxel from the light
// simulator (section 5.2.2, the highest-energy ray), the in-scatter integral of Eq. 3
// becomes the sum of Eq. 6 with a single term, p(x, v, l) dE_omega, where dE_omega is the
// irradiance volume and l the direction volume (src/technique/eikonal/eikonal_light.rs). The phase
// function is Henyey-Greenstein (section 5.1), evaluated "on-the-fly in the fragment
// shader" (section 5.3). Per step of arc length ds the ray gains
//     T(s) sigma_s p(cos theta) dE_omega ds,
// T the transmittance so far (Eq. 5), theta between the light's direction of travel and
// the direction towards the eye. Kept in this include so that view.frag's edit is small.
#ifndef EIKONAL_SCATTER_GLSL
#define EIKONAL_SCATTER_GLSL

#ifndef EIKONAL_LIGHT_SET
#define EIKONAL_LIGHT_SET 1
#endif
layout(set = EIKONAL_LIGHT_SET, binding = BINDING_EIKONAL_IRRADIANCE) uniform sampler3D light_irradiance;
layout(set = EIKONAL_LIGHT_SET, binding = BINDING_EIKONAL_LIGHT_DIR) uniform sampler3D light_direction;

// Henyey & Greenstein 1941: normalized over the sphere, mean cosine g.
float henyey_greenstein(float cos_theta, float g) {
    float d = 1.0 + g * g - 2.0 * g * cos_theta;
    return (1.0 - g * g) / (4.0 * PI * d * sqrt(max(d, 1e-12)));
}

// The simulated light at x in the irradiance volume spanning light_min..light_max, by
// trilinear interpolation (the track-length deposits of light_step.glsl are splatted
// trilinearly, so no voxel inside the lit region is a hole and the interpolation is linear:
// the light of several runs, lights and channels adds up exactly). `irradiance` is the sum
// of every ray's dE_omega (Eqs. 6-7 sum over j); `dir` is the mean direction of travel,
// sum_j w_j l_j / sum_j w_j (w = E_r + E_g + E_b), whose length is the mean cosine between
// the rays: dot(n, -dir) * irradiance is Eq. 7's sum_j cos(theta_j) dE_omega,j for a
// Lambertian receiver. Returns false where no light arrives.
bool light_at(vec3 x, vec3 light_min, vec3 light_max, out vec3 irradiance, out vec3 dir) {
    irradiance = vec3(0.0);
    dir = vec3(0.0);
    if (any(lessThan(x, light_min)) || any(greaterThanEqual(x, light_max))) return false;
    ivec3 size = textureSize(light_irradiance, 0);
    vec3 u = (x - light_min) / (light_max - light_min) * vec3(size) - 0.5;
    ivec3 i0 = ivec3(floor(u));
    vec3 f = u - vec3(i0);
    vec4 vector_sum = vec4(0.0);
    for (int c = 0; c < 8; ++c) {
        ivec3 o = ivec3(c & 1, (c >> 1) & 1, (c >> 2) & 1);
        ivec3 q = clamp(i0 + o, ivec3(0), size - 1);
        vec3 w3 = mix(1.0 - f, f, vec3(o));
        float w = w3.x * w3.y * w3.z;
        irradiance += w * texelFetch(light_irradiance, q, 0).rgb;
        vector_sum += w * texelFetch(light_direction, q, 0);
    }
    if (!(vector_sum.w > 0.0)) return false;
    dir = vector_sum.xyz / vector_sum.w;
    return true;
}

// In-scattered radiance per metre at x towards the eye (to_eye: unit), before sigma_s and
// transmittance: p(cos theta) dE_omega.
vec3 inscatter(vec3 x, vec3 to_eye, vec3 light_min, vec3 light_max, float g) {
    vec3 e, l;
    if (!light_at(x, light_min, light_max, e, l)) return vec3(0.0);
    // The mean direction stands for every ray (the paper keeps one ray per voxel, 5.2.2).
    l = dot(l, l) > 1e-12 ? normalize(l) : vec3(0.0);
    return henyey_greenstein(dot(l, to_eye), g) * e;
}
#endif
