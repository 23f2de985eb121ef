#version 450
// Caustic textures from the photon buffer, on the GPU (Hu & Qin 2007 §3.2). The paper reads
// the photon buffer back with glReadPixels and increments TEX_CAUSTICS_k at (u, v) on the
// CPU; here one point is drawn per photon-buffer pixel, its vertex shader fetches (u, v, k)
// (vertex texture fetch) and places the point on texel (u, v) of TEX_CAUSTICS_k, and
// additive blending counts the photons (alpha) and sums their power (rgb). One draw per
// rectangle (array layer): a photon of another rectangle is dropped.
#include "prism_shared.glsl"
layout(set = 0, binding = 0) uniform sampler2DArray photons;
layout(set = 0, binding = 1) uniform sampler2DArray photon_flux;
layout(push_constant) uniform PhotonScatterPushBlock { PhotonScatterPush pc; };
layout(location = 0) flat out vec4 out_photon;

void main() {
    int grid = int(pc.info.x);
    int per_face = grid * grid;
    int layer = gl_VertexIndex / per_face;
    int texel = gl_VertexIndex % per_face;
    ivec3 at = ivec3(texel % grid, texel / grid, layer);
    vec4 p = texelFetch(photons, at, 0);
    out_photon = vec4(0.0);
    gl_PointSize = 1.0;
    if (uint(p.z + 0.5) != pc.info.z) {
        gl_Position = vec4(2.0, 2.0, 2.0, 1.0);   // outside the clip volume: culled
        return;
    }
    // A point of size 1 covers exactly the texel whose square holds its centre.
    gl_Position = vec4(p.xy * 2.0 - 1.0, 0.5, 1.0);
    out_photon = vec4(texelFetch(photon_flux, at, 0).rgb, 1.0);
}
