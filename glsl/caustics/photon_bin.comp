#version 450
// The photons summed per caustic texel before Hu & Qin 2007 §3.2's filter. The filter is
// linear in the counts p(u, v), and a photon's kernel depends only on its texel, so the
// photons that land in one texel need one kernel between them, weighted by their sum: this
// pass adds every photon's power and its count to its texel and marks the texel's first
// photon in photon-buffer order (an atomic max of its complement: the winner does not depend
// on the order the device runs them in, nor then does the draw order of
// photon_scatter.glsl's points). Where a ball lens focuses light, many photons share a texel:
// on caustic_sphere 12 156 photons land in 672 texels of 512^2.
//
// The power is summed in 64-bit fixed point, integer atomics on two 32-bit words, so that the
// sum does not depend on the order of the additions either (float atomics would round in
// whatever order the device runs them, and an image would change in its last bits from run to
// run). One step is pc.sum_unit.x W, the brightest photon the lights can send over 2^32
// (photon_buffer.rs `fixed_point_step`): a photon's power keeps a float's 24 bits down to
// 1/256 of that, and 2^32 such photons fit in a texel.
#include "prism_shared.glsl"
#include "photon_sums.glsl"
layout(local_size_x = 64) in;
layout(set = 0, binding = 0) uniform sampler2DArray photons;
layout(set = 0, binding = 1) uniform sampler2DArray photon_flux;
layout(set = 0, binding = 2, r32ui) uniform uimage2DArray sums;
layout(push_constant) uniform PhotonScatterPushBlock { PhotonScatterPush pc; };

// Adds `steps` (a non-negative whole number below 2^64, as a float) to the 64-bit sum in
// layers lo, lo + 1: the carry out of the low word is known from the value it held before
// this addition, so the high word receives exactly the carries, in whatever order they come.
void add_fixed(ivec2 t, int lo, float steps) {
    const float WORD = 4294967296.0;
    float high = floor(steps / WORD);
    // Exact: both terms are multiples of steps' last place, and the difference is below 2^32.
    uint low = uint(floor(steps - high * WORD + 0.5));
    uint before = imageAtomicAdd(sums, ivec3(t, lo), low);
    uint carry = before + low < before ? 1u : 0u;
    // Mostly 0 (a photon within the bound is below 2^32 steps, and the low word wraps once
    // per 2^32 steps summed): lavapipe then skips the lane's atomic, 0.87x the pass on
    // caustic_bunny (docs/BENCHMARKS.md).
    uint add = uint(high) + carry;
    if (add != 0u) imageAtomicAdd(sums, ivec3(t, lo + 1), add);
}

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
    // photon_buffer.frag writes no NaN, Inf or negative power; clamp to what two words hold.
    vec3 steps = clamp(texelFetch(photon_flux, at, 0).rgb / pc.sum_unit.x, 0.0, 1.8e19);
    int base = SUM_LAYERS * (k - 1);
    for (int c = 0; c < SUM_CHANNELS; ++c) {
        add_fixed(t, base + 2 * c, steps[c]);
    }
    imageAtomicAdd(sums, ivec3(t, base + SUM_COUNT), 1u);
    imageAtomicMax(sums, ivec3(t, base + SUM_OWNER), ~uint(index));
}
