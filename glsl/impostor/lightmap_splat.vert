#version 450
// Light-map caustics (Szirmay-Kalos et al. 2005, §5): "we render as many small quadrilaterals
// ... or point sprites as texels the caustic map has"; the vertex shader reads the caustic map
// (vertex texture fetch), centres the sprite at the photon hit's (u, v) in the receiver's
// texture space and "moves the quadrilateral out of the clipping region if the alpha is
// negative". One point sprite per caustic-map texel, its Gaussian normalized over the texels
// it covers (lightmap_splat.glsl). With BLOCKS (render.impostor_lightmap.block_splats) the
// photons of the 2 x 2 blocks that lightmap_splat_block.vert draws as one sprite are left out
// here.
#include "lightmap_splat.glsl"
layout(constant_id = 0) const uint BLOCKS = 0u;
layout(location = 0) flat out vec3 out_irradiance;   // power / texel area / weight sum
layout(location = 1) flat out vec2 out_center;       // splat centre in light-map pixels

void drop_vertex() {
    gl_Position = vec4(2.0, 2.0, 2.0, 1.0);   // outside the clip volume: culled
    gl_PointSize = 1.0;
    out_irradiance = vec3(0.0);
    out_center = vec2(0.0);
}

void main() {
    uint size = pc.info.y;
    ivec2 texel = ivec2(uint(gl_VertexIndex) % size, uint(gl_VertexIndex) / size);
    vec2 uv, lo, hi;
    vec3 irradiance;
    if (!photon_at(texel, uv) || (BLOCKS != 0u && block_fits(texel / 2, lo, hi))
        || !splat_irradiance(texel, uv * pc.params.y, irradiance)) {
        drop_vertex();
        return;
    }
    out_irradiance = irradiance;
    out_center = uv * pc.params.y;
    gl_Position = vec4(uv * 2.0 - 1.0, 0.0, 1.0);
    // Pixel centres up to r + 1/2 from the centre along each axis: the whole disc.
    gl_PointSize = 2.0 * ceil(pc.params.x) + 1.0;
}
