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
    float M = 0.0;
    vec3 phi = vec3(0.0);
    // The cell size is twice the initial radius and R only shrinks, so the ball of radius R
    // overlaps at most 2 cells per axis: its photons lie in at most 2x2x2 cells. (With cells
    // of size R the ball can span 3 per axis, and photons beyond the 8 buckets visited were
    // lost, dimming caustics by an amount that depended on where a pixel's visible point fell
    // on the grid.) Buckets visited twice (hash collisions) are skipped so that no photon is
    // counted twice: each photon of the pass is visited at most once, which bounds the loop
    // iterations of an invocation by the photons of a pass (MAX_PHOTONS_PER_PASS in
    // src/reference/mod.rs says why that bound matters).
    ivec3 lo = grid_cell(p - vec3(R)), hi = grid_cell(p + vec3(R));
    uint visited[8];   // 2x2x2 cells at most (see above)
    uint n_visited = 0u;
    for (int z = lo.z; z <= hi.z; ++z)
    for (int y = lo.y; y <= hi.y; ++y)
    for (int x = lo.x; x <= hi.x; ++x) {
        uint bucket = grid_bucket(ivec3(x, y, z));
        bool seen = false;
        for (uint k = 0u; k < n_visited; ++k) seen = seen || visited[k] == bucket;
        if (seen || n_visited >= 8u) continue;   // never taken: the cells are slightly larger than 2 R0
        visited[n_visited++] = bucket;
        uint i = heads[bucket];
        for (uint guard = 0u; i != END_OF_LIST && guard < ref.photon.y; ++guard) {
            Photon ph = photons[i];
            vec3 q = ph.pos.xyz - p;
            // Only photons arriving on the side the camera sees.
            if (dot(q, q) <= R * R && dot(ph.dir.xyz, n) < 0.0) {
                M += 1.0;
                phi += ph.flux.rgb;
            }
            i = floatBitsToUint(ph.pos.w);
        }
    }
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
