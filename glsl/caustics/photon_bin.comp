#version 450
#extension GL_EXT_shader_atomic_float : require
// The photons summed per caustic texel before Hu & Qin 2007 §3.2's filter. The filter is
// linear in the counts p(u, v), and a photon's kernel depends only on its texel, so the
// photons that land in one texel need one kernel between them, weighted by their sum: this
// pass adds every photon's power and its count to its texel (float atomics) and marks the
// texel's first photon in photon-buffer order (an atomic max of its complement: the winner
// does not depend on the order the device runs them in, nor then does the draw order of
// photon_scatter.vert's points). Where a ball lens focuses light, many photons share a texel:
// on caustic_sphere 12 156 photons land in 672 texels of 512^2.
#include "prism_shared.glsl"
layout(local_size_x = 64) in;
layout(set = 0, binding = 0) uniform sampler2DArray photons;
layout(set = 0, binding = 1) uniform sampler2DArray photon_flux;
// Layer 4 (k - 1) + c: channel c of rectangle k's sums (c = 3: the count).
layout(set = 0, binding = 2, r32f) uniform image2DArray sums;
// 0: no photon; else ~(the first photon's index).
layout(set = 0, binding = 3, r32ui) uniform uimage2DArray owner;
layout(push_constant) uniform PhotonScatterPushBlock { PhotonScatterPush pc; };

void main() {
    int grid = int(pc.info.x);
    int per_face = grid * grid;
    int index = int(gl_GlobalInvocationID.x);
    if (index >= per_face * int(pc.info.y)) return;
    ivec3 at = ivec3(index % per_face % grid, index % per_face / grid, index / per_face);
    vec4 p = texelFetch(photons, at, 0);
    int k = int(p.z + 0.5);
    if (k == 0) return;
    float size = pc.params.z;
    ivec2 t = clamp(ivec2(floor(p.xy * size)), ivec2(0), ivec2(int(size) - 1));
    vec3 flux = texelFetch(photon_flux, at, 0).rgb;
    int base = 4 * (k - 1);
    imageAtomicAdd(sums, ivec3(t, base), flux.r);
    imageAtomicAdd(sums, ivec3(t, base + 1), flux.g);
    imageAtomicAdd(sums, ivec3(t, base + 2), flux.b);
    imageAtomicAdd(sums, ivec3(t, base + 3), 1.0);
    imageAtomicMax(owner, ivec3(t, k - 1), ~uint(index));
}
