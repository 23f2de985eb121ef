#version 450
// HistoPyramid traversal (Ihrke et al. 2007, section 5.2.3; Ziegler et al. 2006): output
// slot j descends from the top, at each level choosing the child whose running prefix sum
// exceeds j, and ends on the input entry it belongs to and its index among that entry's
// outputs (0 for a retained patch, 0..3 for the sub-patches of a tessellated one).
// Dispatched indirectly over `next` outputs.
#include "histopyramid.glsl"
layout(local_size_x = LIGHT_GROUP) in;

// The child of `node` whose outputs hold output `rest` of the node, given the four
// children's counts; `rest` becomes the output's index within that child. A live node's live
// children come first and `rest` is below their sum, so the descent stops before any stale
// entry past them.
uint descend(uint node, uvec4 counts, inout uint rest) {
    uint child = 4u * node;
    for (uint c = 0u; c < 4u; ++c) {
        child = 4u * node + c;
        if (rest < counts[c]) break;
        rest -= counts[c];
    }
    return child;
}

void main() {
    uint j = gl_GlobalInvocationID.x;
    if (j >= state.next + state.spill_new) return;
    uint node = 0u;
    uint rest = j;
    // The levels above the classes, then the classes (level 0) apart: a CPU device loads
    // both arrays for every child where one loop chooses between them per level.
    for (uint k = hp_top(); k >= 2u; --k) {
        uint len = hp_level_len(k - 1u), offset = hp_level_offset(k - 1u);
        uvec4 counts;
        for (uint c = 0u; c < 4u; ++c) {
            uint i = 4u * node + c;
            counts[c] = i < len ? levels[offset + i] : 0u;
        }
        node = descend(node, counts, rest);
    }
    // Level 0 unmasked: `count` is already the output count here.
    uvec4 counts;
    for (uint c = 0u; c < 4u; ++c) {
        uint i = 4u * node + c;
        counts[c] = i < CAPACITY ? classes[i] : 0u;
    }
    node = descend(node, counts, rest);
    pairs[j] = uvec2(node, rest);
}
