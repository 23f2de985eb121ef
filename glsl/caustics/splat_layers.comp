#version 450
// Caustics mapping's splat draws (Shah et al. 2007, §III.F), one invocation per caustic-atlas
// layer, after splat_hits.comp has counted the records landing in each layer: a layer that
// records reach draws its light's records (splat.vert keeps its own, in record order, so the
// additions, and the map, are the same from run to run), one that none reach draws nothing;
// its clear draw (a full-screen triangle writing 0) runs where this frame has records or the
// layer's last drawn frame had. A layer that neither reached holds zeros already, and its
// 512^2 RGBA32F texels are not cleared again (on a CPU device, clearing the five faces of a
// cube that a ball's caustic misses took more than half the pass). The first frame clears
// every layer: `seen` starts at 1.
#include "common.glsl"
layout(local_size_x = REF_WORKGROUP) in;
layout(set = 0, binding = CAUSTIC_BINDING_COUNTS, std430) readonly buffer Counts { uint counts[]; };
layout(set = 0, binding = CAUSTIC_BINDING_SPANS, std430) readonly buffer Spans { uvec2 spans[]; };
layout(set = 0, binding = CAUSTIC_BINDING_SPLAT_DRAWS, std430) writeonly buffer SplatDraws { uvec4 splat_draws[]; };
layout(set = 0, binding = CAUSTIC_BINDING_CLEAR_DRAWS, std430) writeonly buffer ClearDraws { uvec4 clear_draws[]; };
layout(set = 0, binding = CAUSTIC_BINDING_SEEN, std430) buffer Seen { uint seen[]; };

void main() {
    uint layer = gl_GlobalInvocationID.x;
    if (layer >= counts.length()) return;
    uint n = counts[layer];
    // VkDrawIndirectCommand: vertexCount, instanceCount, firstVertex, firstInstance.
    splat_draws[layer] = uvec4(n > 0u ? spans[layer].y : 0u, 1u, spans[layer].x, 0u);
    clear_draws[layer] = uvec4(n > 0u || seen[layer] > 0u ? 3u : 0u, 1u, 0u, 0u);
    seen[layer] = n;
}
