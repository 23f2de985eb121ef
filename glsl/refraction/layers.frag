#version 450
// One depth+normal layer of the refractors (Wyman 2005 §3.2 / Fig. 3a,d; Hu & Qin 2007 Fig. 4
// "initial pass"). Which surface survives is set by the pipeline (culling, depth compare).
#include "frame.glsl"
layout(location = 0) in vec3 in_normal;
// RT0 (RGBA32F): xyz = unit outward world normal (0 where no refractor: the coverage mask),
// w = 0.
layout(location = 0) out vec4 out_layer;
void main() {
    vec3 n = in_normal;
    float len = length(n);
    n = len > 1e-20 ? n / len : vec3(0.0, 1.0, 0.0);
    out_layer = vec4(n, 0.0);
}
