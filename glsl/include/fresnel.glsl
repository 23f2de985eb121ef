// Exact Fresnel equations for unpolarised light.
#ifndef PRISM_FRESNEL_GLSL
#define PRISM_FRESNEL_GLSL

// Dielectric reflectance for cos_i = cos(theta_i) >= 0 and eta = n_i / n_t.
// Returns 1 under total internal reflection.
float fresnel_dielectric(float cos_i, float eta) {
    cos_i = clamp(cos_i, 0.0, 1.0);
    float sin2_t = eta * eta * (1.0 - cos_i * cos_i);
    if (sin2_t >= 1.0) return 1.0;
    float cos_t = sqrt(max(1.0 - sin2_t, 0.0));
    // r_s and r_p with n_i, n_t scaled by 1/n_t (only the ratio matters).
    float rs = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    float rp = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    return clamp(0.5 * (rs * rs + rp * rp), 0.0, 1.0);
}

// Conductor reflectance, exact for complex index eta + i k relative to the outside medium
// (e.g. pbrt-v3 FrConductor), per channel.
vec3 fresnel_conductor(float cos_i, vec3 eta, vec3 k) {
    cos_i = clamp(cos_i, 0.0, 1.0);
    float c2 = cos_i * cos_i, s2 = 1.0 - c2;
    vec3 eta2 = eta * eta, k2 = k * k;
    vec3 t0 = eta2 - k2 - s2;
    vec3 a2b2 = sqrt(max(t0 * t0 + 4.0 * eta2 * k2, vec3(0.0)));
    vec3 t1 = a2b2 + c2;
    vec3 a = sqrt(max(0.5 * (a2b2 + t0), vec3(0.0)));
    vec3 t2 = 2.0 * cos_i * a;
    vec3 rs = (t1 - t2) / max(t1 + t2, vec3(1e-12));
    vec3 t3 = c2 * a2b2 + s2 * s2;
    vec3 t4 = t2 * s2;
    vec3 rp = rs * (t3 - t4) / max(t3 + t4, vec3(1e-12));
    return clamp(0.5 * (rp + rs), 0.0, 1.0);
}

// The conductor Fresnel approximation of Szirmay-Kalos et al. 2005, §3 (after Lazanyi &
// Szirmay-Kalos 2005): Schlick's form with F(0) from the complex index n + i k,
//   F = ((n-1)^2 + k^2 + 4 n (1 - cos)^5) / ((n+1)^2 + k^2),
// exact at normal incidence and at grazing incidence (F = 1), per channel.
vec3 fresnel_conductor_approx(float cos_i, vec3 eta, vec3 k) {
    float c = 1.0 - clamp(cos_i, 0.0, 1.0);
    float c5 = (c * c) * (c * c) * c;
    vec3 num = (eta - 1.0) * (eta - 1.0) + k * k + 4.0 * eta * c5;
    vec3 den = (eta + 1.0) * (eta + 1.0) + k * k;
    return clamp(num / max(den, vec3(1e-12)), 0.0, 1.0);
}
#endif
