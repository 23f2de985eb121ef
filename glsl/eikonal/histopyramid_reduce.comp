#version 450
// HistoPyramid build (Ihrke et al. 2007, section 5.2.3; Ziegler et al. 2006): one dispatch
// per level k = 1 .. top, each entry the sum of its four children on level k - 1, over the
// live entries only (dispatched indirectly from state.level_args).
#include "histopyramid.glsl"
layout(local_size_x = LIGHT_GROUP) in;
layout(push_constant) uniform Push { uint level; } push;

void main() {
    uint i = gl_GlobalInvocationID.x;
    uint k = push.level;
    if (i >= hp_live_len(k, state.count)) return;
    uint sum = 0u;
    for (uint c = 0u; c < 4u; ++c) sum += hp_value(k - 1u, 4u * i + c);
    levels[hp_level_offset(k) + i] = sum;
}
