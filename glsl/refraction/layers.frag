#version 450
// One depth+normal layer of the refractors (Wyman 2005 §3.2 / Fig. 3a,d; Hu & Qin 2007 Fig. 4
// "initial pass"). Which surface survives is set by the pipeline (culling, depth compare) and,
// for LAYER_SECOND, by peeling against the G-buffer's first surface.
#include "frame.glsl"
layout(constant_id = 0) const uint MODE = LAYER_FRONT;
layout(set = 1, binding = BINDING_GBUF_DEPTH) uniform sampler2D gbuf_depth;
layout(location = 0) in vec3 in_normal;
layout(location = 1) in float in_d_n;
// RT0 (RGBA32F): xyz = unit outward world normal (0 where no refractor: the coverage mask),
// w = d_N interpolated from the vertices (Wyman's front layer; 0 otherwise).
layout(location = 0) out vec4 out_layer;
void main() {
    if (MODE == LAYER_SECOND) {
        // Depth peeling: keep only surfaces strictly behind the first one (reversed Z: a
        // smaller depth is further). The margin (1e-6 relative distance) rejects the first
        // surface itself, which the G-buffer rasterised with the same transform.
        float first = texelFetch(gbuf_depth, ivec2(gl_FragCoord.xy), 0).r;
        if (gl_FragCoord.z >= first * (1.0 - 1e-6)) discard;
    }
    vec3 n = in_normal;
    float len = length(n);
    n = len > 1e-20 ? n / len : vec3(0.0, 1.0, 0.0);
    out_layer = vec4(n, in_d_n);
}
