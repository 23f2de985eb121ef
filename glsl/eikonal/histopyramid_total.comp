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
    state.requested = total;
    state.dropped += total - next;
    state.next = next;
    // The output list is the next step's input. The traversal below does not need the old
    // count: it only descends into children whose partial sums it has counted.
    state.count = next;
    hp_write_level_args(next);
    state.args = uvec4((next + LIGHT_GROUP - 1u) / LIGHT_GROUP, 1u, 1u, 0u);
    state.peak = max(state.peak, next);
    if (state.step < HISTORY_LEN) history[state.step] = next;
    state.step += 1u;
}
