#version 450
// Caustics mapping's splat (Shah et al. 2007, §III.F: "textured point primitives with a
// gaussian fall-off"): one point per grid vertex, drawn into the caustic-atlas layer its
// record (splat_hits.comp) lands in; the records of other layers are dropped here. The
// indirect draw (splat_layers.comp) covers the layer's light's records, from its first, and
// is empty where no record lands in the layer.
#include "common.glsl"

layout(set = 0, binding = CAUSTIC_BINDING_SPLATS, std430) readonly buffer Splats { GpuCausticSplat splats[]; };
layout(push_constant) uniform CausticDrawPushBlock { CausticDrawPush pc; };

layout(location = 0) flat out vec3 out_flux;
layout(location = 1) flat out vec3 out_splat;

void main() {
    GpuCausticSplat r = splats[uint(gl_VertexIndex)];
    if (r.position.w != float(pc.dest.x)) {
        gl_Position = vec4(2.0, 2.0, 2.0, 1.0);   // outside the clip volume: the point is culled
        gl_PointSize = 1.0;
        out_flux = vec3(0.0);
        out_splat = vec3(0.0);
        return;
    }
    float sigma = r.flux.w;
    gl_Position = vec4(r.position.xyz, 1.0);
    gl_PointSize = 2.0 * ceil(3.0 * sigma) + 1.0;
    out_flux = r.flux.rgb;
    out_splat = vec3((r.position.xy * 0.5 + 0.5) * float(pc.dest.z), 1.0 / (2.0 * sigma * sigma));
}
