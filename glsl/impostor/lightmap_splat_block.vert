#version 450
// One point sprite for the photons of a 2 x 2 block of caustic-map texels whose centres lie
// close together on the light map (render.impostor_lightmap.block_splats; `block_fits` in
// lightmap_splat.glsl): its fragments add the four photons' Gaussians, each normalized as its
// own sprite's would be, so the light map gets the same sums (up to the order of the float
// additions) for a quarter of the sprites. A CPU device pays about 0.6 us to set up a sprite
// whatever its size. The other blocks' photons are drawn one by one by lightmap_splat.vert.
#include "lightmap_splat.glsl"
layout(location = 0) flat out vec4 out_irradiance[4];   // rgb: power / texel area / weight sum
layout(location = 4) flat out vec4 out_centers[2];      // photon i's centre: [i / 2].xy or .zw

void main() {
    uint blocks = (pc.info.y + 1u) / 2u;
    ivec2 b = ivec2(uint(gl_VertexIndex) % blocks, uint(gl_VertexIndex) / blocks);
    vec2 lo, hi;
    for (int i = 0; i < 4; ++i) out_irradiance[i] = vec4(0.0);
    out_centers[0] = vec4(0.0);
    out_centers[1] = vec4(0.0);
    if (!block_fits(b, lo, hi)) {
        gl_Position = vec4(2.0, 2.0, 2.0, 1.0);   // outside the clip volume: culled
        gl_PointSize = 1.0;
        return;
    }
    vec2 centers[4];
    for (int i = 0; i < 4; ++i) {
        ivec2 texel = 2 * b + ivec2(i & 1, i >> 1);
        vec2 uv;
        vec3 irradiance;
        centers[i] = vec2(0.0);
        if (photon_at(texel, uv)) {
            centers[i] = uv * pc.params.y;
            if (splat_irradiance(texel, centers[i], irradiance)) out_irradiance[i] = vec4(irradiance, 1.0);
        }
    }
    out_centers[0] = vec4(centers[0], centers[1]);
    out_centers[1] = vec4(centers[2], centers[3]);
    vec2 mid = 0.5 * (lo + hi);
    gl_Position = vec4(mid / pc.params.y * 2.0 - 1.0, 0.0, 1.0);
    // Pixel centres up to r + 1/2 from every centre along each axis: every photon's disc.
    gl_PointSize = max(hi.x - lo.x, hi.y - lo.y) + 2.0 * ceil(pc.params.x) + 1.0;
}
