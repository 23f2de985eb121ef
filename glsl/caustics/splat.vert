#version 450
// Caustics mapping's splat (Shah et al. 2007, §III.F: "textured point primitives with a
// gaussian fall-off"): one point per grid vertex that landed in the caustic-atlas layer
// drawn. The indirect draw's first vertex is where that layer's list of records begins
// (splat_hits.glsl, splat_layers.comp), so gl_VertexIndex indexes the lists.
#include "common.glsl"

layout(set = 0, binding = CAUSTIC_BINDING_SPLATS, std430) readonly buffer Splats { GpuCausticSplat splats[]; };
layout(set = 0, binding = CAUSTIC_BINDING_ORDER, std430) readonly buffer Order { uint order[]; };
layout(push_constant) uniform CausticDrawPushBlock { CausticDrawPush pc; };

layout(location = 0) flat out vec3 out_flux;
layout(location = 1) flat out vec3 out_splat;

void main() {
    GpuCausticSplat r = splats[order[uint(gl_VertexIndex)]];
    float sigma = r.flux.w;
    gl_Position = vec4(r.position.xyz, 1.0);
    gl_PointSize = 2.0 * ceil(3.0 * sigma) + 1.0;
    out_flux = r.flux.rgb;
    out_splat = vec3((r.position.xy * 0.5 + 0.5) * float(pc.dest.x), 1.0 / (2.0 * sigma * sigma));
}
