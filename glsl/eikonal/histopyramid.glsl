// A 1D, 4-ary HistoPyramid over a list of output counts (Ziegler et al. 2006, extended to
// data expansion by Ihrke et al. 2007, section 5.2.3). Level 0 holds each input entry's
// count (0 eliminate, 1 retain, 4 tessellate); entry i of level k >= 1 is the sum of entries
// 4i .. 4i+3 of level k - 1; the top level is one entry, the total output count.
//
// Why 1D and not the paper's 2D pyramid: the paper stores the patch list in a 2D texture
// because Shader Model 3 hardware had no buffers; in a storage buffer the list is 1D and a
// 4-ary reduction of it has the same depth (log4 N) and the same traversal as the 2D
// pyramid's 2x2 quads, without padding the list to a square power of two.
// Mirrored exactly on the CPU by src/technique/eikonal/histopyramid.rs (tests/eikonal_light.rs).
#include "prism_shared.glsl"

// Entries of level 0: the list capacity, also the most outputs (the clamp).
layout(constant_id = 0) const uint CAPACITY = 4u;
// Entries of the per-step history of output counts.
layout(constant_id = 1) const uint HISTORY_LEN = 1u;
// Entries of the spill list (outputs past CAPACITY, continued by a later run); 0: none, the
// outputs past CAPACITY are dropped and counted.
layout(constant_id = 19) const uint SPILL_CAPACITY = 0u;

layout(std430, set = 0, binding = LIGHT_BINDING_STATE) buffer State { HpState state; };
layout(std430, set = 0, binding = LIGHT_BINDING_CLASSES) buffer Classes { uint classes[]; };
layout(std430, set = 0, binding = LIGHT_BINDING_LEVELS) buffer Levels { uint levels[]; };
// Output slot j -> (input entry, index among that entry's outputs).
layout(std430, set = 0, binding = LIGHT_BINDING_PAIRS) buffer Pairs { uvec2 pairs[]; };
layout(std430, set = 0, binding = LIGHT_BINDING_HISTORY) buffer History { uint history[]; };

uint hp_level_len(uint k) {
    uint n = CAPACITY;
    for (uint i = 0u; i < k; ++i) n = (n + 3u) / 4u;
    return n;
}

// Offset of level k >= 1 in `levels` (levels 1, 2, ... are stored back to back).
uint hp_level_offset(uint k) {
    uint n = CAPACITY, offset = 0u;
    for (uint i = 1u; i < k; ++i) {
        n = (n + 3u) / 4u;
        offset += n;
    }
    return offset;
}

// The top level's index (its length is 1); CAPACITY >= 4 makes it >= 1.
uint hp_top() {
    uint n = CAPACITY, k = 0u;
    while (n > 1u) {
        n = (n + 3u) / 4u;
        ++k;
    }
    return k;
}

// Entries of level k that an input list of `count` entries makes live: ceil(count / 4^k).
// Only these are built (histopyramid_reduce.comp is dispatched over them, indirectly), so
// a step's pyramid costs O(count) rather than O(CAPACITY) (Ziegler et al. 2006 build the
// whole texture because a fragment pass cannot be sized on the device; a compute dispatch
// can).
uint hp_live_len(uint k, uint count) {
    uint n = count;
    for (uint i = 0u; i < k; ++i) n = (n + 3u) / 4u;
    return n;
}

// The indirect arguments of every reduction level for an input list of `count` entries
// (level k + 1 in level_args[k]); written where `count` is set, so that the build that
// follows needs no CPU.
void hp_write_level_args(uint count) {
    uint n = count;
    for (uint k = 0u; k < HP_MAX_LEVELS; ++k) {
        n = (n + 3u) / 4u;
        state.level_args[k] = uvec4((n + LIGHT_GROUP - 1u) / LIGHT_GROUP, 1u, 1u, 0u);
    }
}

// Entry i of level k during the build over `state.count` inputs; 0 beyond the live length
// (entries past it are stale from an earlier, longer list).
uint hp_value(uint k, uint i) {
    if (k == 0u) return i < state.count ? classes[i] : 0u;
    return i < hp_live_len(k, state.count) ? levels[hp_level_offset(k) + i] : 0u;
}
