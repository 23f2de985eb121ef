// Buffers of stochastic progressive photon mapping (Hachisuka & Jensen 2009), used for the
// reference's caustics: per-pixel statistics and visible points, the photons of the current
// iteration, and a hashed grid of linked lists over them.
#ifndef PRISM_REFERENCE_SPPM_GLSL
#define PRISM_REFERENCE_SPPM_GLSL
#include "scene.glsl"
#include "photon_grid.glsl"

layout(set = 0, binding = REF_BINDING_ACCUM, std430) buffer Accum { vec4 accum[]; };   // sum of L, sample count
layout(set = 0, binding = REF_BINDING_PIXELS, std430) buffer Pixels { PixelState pixels[]; };
layout(set = 0, binding = REF_BINDING_COUNTERS, std430) buffer Counters { uint photon_count; };
layout(set = 0, binding = REF_BINDING_DEBUG, std430) buffer Debug { vec4 debug_data[]; };
layout(set = 0, binding = REF_BINDING_STATS, std430) buffer Stats { uint ref_stats[]; };

// Paths that end at volume.glsl's step cap are counted in the kernel's slot.
#ifdef REF_STAT_STEP_CAP_SLOT
#define VOLUME_STEP_CAP_REACHED() atomicAdd(ref_stats[REF_STAT_STEP_CAP_SLOT], 1u)
#endif

// Whether the driver's loop budget ran out in this invocation, counted in ref_stats[slot].
// lavapipe gives the invocations it runs in lockstep 65535 loop iterations in all, over every
// loop, and once they are spent every later loop runs its body once and stops
// (tests/loop_limit.rs measures it): the paths of a cut invocation are silently short. Called
// last in a kernel, this loop of ref_stats[REF_STAT_CANARY_TRIPS] = 2 trips (from a buffer,
// so that it cannot be unrolled) then runs once. Its second trip needs 2 iterations of the
// budget left, so it also fires when exactly 1 was left and nothing was cut, and it fires
// for every lane run in lockstep with a cut one: the count over-states cut invocations (by
// at most the vector width per cut one) and never misses one. Drivers without such a limit
// never fire it.
void loop_canary(uint slot) {
    uint trips = 0u;
    for (uint k = 0u; k < ref_stats[REF_STAT_CANARY_TRIPS]; ++k) ++trips;
    if (trips < ref_stats[REF_STAT_CANARY_TRIPS]) atomicAdd(ref_stats[slot], 1u);
}
#endif
