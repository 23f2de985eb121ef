#version 450
// Stochastic progressive photon mapping update (Hachisuka & Jensen 2009, Sec. 4, with the
// progressive radius reduction of Hachisuka et al. 2008, Eqs. 6-8): each pixel's visible
// point of this iteration collects the photons within its radius R; then
//   N' = N + alpha M,  R' = R sqrt((N + alpha M) / (N + M)),  tau' = (tau + Phi) (R'/R)^2,
// and the caustic radiance is tau / (pi R^2 iterations) (resolved on the host).
#include "sppm.glsl"

// Pixel px's progressive update from this pass's photons.
void gather_pixel(uint px) {
    PixelState st = pixels[px];
    if (st.vp_normal.w < 0.5) return;
    vec3 p = st.vp_pos.xyz;
    vec3 n = st.vp_normal.xyz;
    float R = st.vp_pos.w;
    // The same search as the raytrace technique's (photon_grid.glsl); R only shrinks from
    // its initial radius, at most ref.grid.y.
    float M;
    vec3 phi;
    photons_within(p, n, R, M, phi);
    if (M > 0.0) {
        float alpha = ref.grid.z;
        float N = st.tau_n.w;
        float R2 = R * sqrt((N + alpha * M) / (N + M));
        vec3 tau = (st.tau_n.rgb + finite_or_zero(st.vp_weight.rgb * phi)) * (R2 * R2) / (R * R);
        pixels[px].tau_n = vec4(tau, N + alpha * M);
        pixels[px].vp_pos.w = R2;
    }
}

void main() {
    uint px = invocation_index();
    if (px >= ref.dims.x * ref.dims.y) return;
    gather_pixel(px);
    // After the whole update, whatever returns it takes (sppm.glsl).
    loop_canary(REF_STAT_CUT_GATHER);
}
