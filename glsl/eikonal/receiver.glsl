// A diffuse receiver lit by the eikonal light simulation (Ihrke et al. 2007, Fig. 1 left;
// Eq. 7 with a Lambertian BRDF, one incoming ray per voxel): deferred shading's radiance with
// the simulated light's direct term replaced inside the irradiance volume lo..hi, as
// glsl/eikonal/light_receiver.frag does for the camera's receivers. Branch `eikview`: the
// same at points that eikonal_view's exit rays meet (exact hits, glsl/eikonal/nearby_exit.glsl)
// and in the impostor textures around the volume (glsl/eikonal/nearby_impostor.frag), so
// the caustic and shadow under the volume are seen through it. Keep in step with
// light_receiver.frag. Needs frame.glsl, lighting.glsl and scatter.glsl.
#ifndef EIKONAL_RECEIVER_GLSL
#define EIKONAL_RECEIVER_GLSL

// n: unit normal turned towards the viewer.
vec3 eikonal_receiver(vec3 p, vec3 n, vec3 albedo, vec3 lo, vec3 hi) {
    vec3 radiance = diffuse_radiance(p, n, albedo);
    if (any(lessThan(p, lo)) || any(greaterThanEqual(p, hi)) || frame.info.x == 0u) return radiance;
    // lights[0]'s direct term exactly as diffuse_radiance added it ...
    Light l = frame.lights[0];
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
    float visible = visibility(0u, p, n);
    vec3 direct = e * max(dot(n, wi), 0.0) * visible;
    // ... replaced by the simulated irradiance dE_omega with Lambert's cosine of its ray.
    vec3 sim, l_dir;
    vec3 simulated = light_at(p, lo, hi, sim, l_dir) ? sim * max(dot(n, -l_dir), 0.0) * visible : vec3(0.0);
    radiance += albedo / PI * (simulated - direct);
    return finite_or_zero(max(radiance, vec3(0.0)));
}
#endif
