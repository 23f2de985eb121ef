#version 450
// The HistoPyramid's top is the number of outputs: clamp it to the list capacity (the
// documented clamp: outputs past CAPACITY, the last ones in list order, are dropped and
// counted), write the indirect dispatch arguments for the traversal and the next step, and
// log the count per step, all on the device (no CPU round trip inside a batch).
#include "histopyramid.glsl"
layout(local_size_x = 1) in;

void main() {
    // An empty list built nothing: the top entry is stale then.
    uint total = hp_value(hp_top(), 0u);
    uint next = min(total, CAPACITY);
    // The outputs past the list go to the spill list while it has room: each patch evolves
    // independently of the others (section 5.2), so a later run continues them exactly.
    uint over = total - next;
    uint spill = min(over, SPILL_CAPACITY - state.spilled);
    state.requested = total;
    state.dropped += over - spill;
    state.next = next;
    state.spill_new = spill;
    state.spilled += spill;
    state.out_args = uvec4((next + spill + LIGHT_GROUP - 1u) / LIGHT_GROUP, 1u, 1u, 0u);
    // The output list is the next step's input. The traversal below does not need the old
    // count: it only descends into children whose partial sums it has counted.
    state.count = next;
    hp_write_level_args(next);
    state.args = uvec4((next + LIGHT_GROUP - 1u) / LIGHT_GROUP, 1u, 1u, 0u);
    state.peak = max(state.peak, next);
    if (state.step < HISTORY_LEN) history[state.step] = next;
    state.step += 1u;
}
