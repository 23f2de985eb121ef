#version 450
// HistoPyramid traversal (Ihrke et al. 2007, section 5.2.3; Ziegler et al. 2006): output
// slot j descends from the top, at each level choosing the child whose running prefix sum
// exceeds j, and ends on the input entry it belongs to and its index among that entry's
// outputs (0 for a retained patch, 0..3 for the sub-patches of a tessellated one).
// Dispatched indirectly over `next` outputs.
#include "histopyramid.glsl"
layout(local_size_x = LIGHT_GROUP) in;

void main() {
    uint j = gl_GlobalInvocationID.x;
    if (j >= state.next + state.spill_new) return;
    uint node = 0u;
    uint rest = j;
    // The levels above the classes, then the classes (level 0) apart: a CPU device loads
    // both arrays in every iteration of a loop that chooses between them per level.
    for (uint k = hp_top(); k >= 2u; --k) {
        uint len = hp_level_len(k - 1u), offset = hp_level_offset(k - 1u);
        uint child = 4u * node;
        for (uint c = 0u; c < 4u; ++c) {
            // A live node's children that are live come first, and `rest` is below their
            // sum, so stale entries past them are never reached.
            uint i = 4u * node + c;
            uint v = i < len ? levels[offset + i] : 0u;
            child = i;
            if (rest < v) break;
            rest -= v;
        }
        node = child;
    }
    uint child = 4u * node;
    for (uint c = 0u; c < 4u; ++c) {
        // Level 0 unmasked: `count` is already the output count here, and the valid
        // children come first, so the descent stops before any stale entry (rest is below
        // the sum of the valid ones).
        uint i = 4u * node + c;
        uint v = i < CAPACITY ? classes[i] : 0u;
        child = i;
        if (rest < v) break;
        rest -= v;
    }
    node = child;
    pairs[j] = uvec2(node, rest);
}
