// A diffuse receiver lit by the eikonal light simulation (Ihrke et al. 2007, Fig. 1 left;
// Eq. 7 with a Lambertian BRDF). The irradiance volume covers the volume's box and
// `light_below` metres under it (src/technique/eikonal/eikonal_light.rs), so a floor just under the
// volume lies inside. There the simulated light replaces the direct terms of the lights
// (all of them are simulated): the wavefronts carry both the light that missed the volume
// (I / r^2, the same as the direct term) and the refracted, focused light. The environment
// and the shadow maps of meshes stay as deferred shading computes them. Used by the
// camera's receivers (glsl/eikonal/light_receiver.frag), the points eikonal_view's exit rays
// meet (glsl/eikonal/nearby_exit.glsl) and the impostor textures around the volume
// (glsl/eikonal/nearby_impostor.frag), so that the caustic and shadow under the volume look
// the same directly and through it. Needs frame.glsl, lighting.glsl and scatter.glsl.
#ifndef EIKONAL_RECEIVER_GLSL
#define EIKONAL_RECEIVER_GLSL

bool eikonal_receives(vec3 p, vec3 lo, vec3 hi) {
    return all(greaterThanEqual(p, lo)) && all(lessThan(p, hi)) && light_count() != 0u;
}

// n: unit normal turned towards the viewer. Outside the irradiance volume: deferred shading.
vec3 eikonal_receiver(vec3 p, vec3 n, vec3 albedo, vec3 lo, vec3 hi) {
    if (!eikonal_receives(p, lo, hi)) return diffuse_radiance(p, n, albedo);
    // L = albedo / pi (E_environment + sum_j cos(theta_j) dE_j), Eq. 7 with a Lambertian
    // BRDF. The simulation knows only the volume; the shadow maps of the meshes still darken
    // it, by the unshadowed fraction of the lights' direct irradiance here (exact with one
    // light, a weighted mean of the lights' visibilities with several).
    vec3 direct = vec3(0.0);
    vec3 direct_visible = vec3(0.0);
    for (uint i = 0u; i < light_count(); ++i) {
        GpuLight l = frame.lights[i];
        vec3 wi, e;
        if (is_point_light(l)) {
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
    return finite_or_zero(max(albedo / PI * (environment_irradiance(n) + simulated), vec3(0.0)));
}
#endif
