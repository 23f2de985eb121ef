// Caustic textures from the photon buffer, on the GPU (Hu & Qin 2007 §3.2). The paper reads
// the photon buffer back with glReadPixels, increments TEX_CAUSTICS_k at (u, v) on the CPU,
// then filters every texel:
//   c(u, v) = s * sum_{i,j=-k..k} p(u+i, v+j) sqrt(1 + 2k^2 - (i^2 + j^2)).
// The filter is linear in the counts p, so the same c is each photon's kernel added around its
// own texel: here one point of (2k + 1)^2 texels is drawn per photon-buffer pixel, its vertex
// shader fetches (u, v, k) (vertex texture fetch) and centres the point on texel (u, v) of
// TEX_CAUSTICS_k, the fragment shader weighs each texel by the kernel, and additive blending
// sums. The work is the photons' (2k + 1)^2 texels, not every texel of every texture times
// (2k + 1)^2 taps; texels outside the texture get nothing, as the paper's sum skips them.
// One draw per rectangle (array layer): a photon of another rectangle is dropped.
//
// With MERGED (photon_scatter_merged.vert, render.photon_buffer.merge_texels),
// glsl/caustics/photon_bin.comp has summed the photons of each texel (in fixed point, so the
// same photons give the same sums to the bit); only a texel's first photon draws, carrying
// the sum (its power and count), and empties the texel's sums for the next frame.
#include "prism_shared.glsl"
layout(set = 0, binding = 0) uniform sampler2DArray photons;
layout(set = 0, binding = 1) uniform sampler2DArray photon_flux;
#ifdef MERGED
#include "photon_sums.glsl"
layout(set = 0, binding = 2, r32ui) uniform uimage2DArray sums;
#endif
layout(push_constant) uniform PhotonScatterPushBlock { PhotonScatterPush pc; };
layout(location = 0) flat out vec4 out_photon;
layout(location = 1) flat out ivec2 out_texel;

void main() {
    int grid = int(pc.info.x);
    int per_face = grid * grid;
    int layer = gl_VertexIndex / per_face;
    int texel = gl_VertexIndex % per_face;
    ivec3 at = ivec3(texel % grid, texel / grid, layer);
    vec4 p = texelFetch(photons, at, 0);
    out_photon = vec4(0.0);
    out_texel = ivec2(0);
    gl_PointSize = 1.0;
    if (uint(p.z + 0.5) != pc.info.z) {
        gl_Position = vec4(2.0, 2.0, 2.0, 1.0);   // outside the clip volume: culled
        return;
    }
    // The texel whose square holds (u, v), and a point of odd size 2k + 1 centred on it covers
    // exactly the texels i, j = -k..k around it.
    float size = pc.params.z;
    ivec2 t = clamp(ivec2(floor(p.xy * size)), ivec2(0), ivec2(int(size) - 1));
    // The power (rgb) and the photons counted (a).
    vec4 photon;
#ifdef MERGED
    // Only the texel's first photon draws (another one reads that photon's mark, or the 0 it
    // left after reading the sums: it never finds its own).
    int base = SUM_LAYERS * (int(pc.info.z) - 1);
    if (imageLoad(sums, ivec3(t, base + SUM_OWNER)).r != ~uint(gl_VertexIndex)) {
        gl_Position = vec4(2.0, 2.0, 2.0, 1.0);
        return;
    }
    // The power from its 64-bit fixed point (photon_bin.comp), the count as it is.
    for (int c = 0; c < 3; ++c) {
        int at = base + 2 * min(c, SUM_CHANNELS - 1);
        float low = float(imageLoad(sums, ivec3(t, at)).r);
        float high = float(imageLoad(sums, ivec3(t, at + 1)).r);
        photon[c] = (high * 4294967296.0 + low) * pc.sum_unit.x;
    }
    photon.a = float(imageLoad(sums, ivec3(t, base + SUM_COUNT)).r);
    for (int l = 0; l < SUM_LAYERS; ++l) {
        imageStore(sums, ivec3(t, base + l), uvec4(0u));
    }
#else
    photon = vec4(texelFetch(photon_flux, at, 0).rgb, 1.0);
#endif
    gl_Position = vec4((vec2(t) + 0.5) / size * 2.0 - 1.0, 0.5, 1.0);
    gl_PointSize = float(2u * pc.info.w + 1u);
    out_texel = t;
    out_photon = photon;
}
