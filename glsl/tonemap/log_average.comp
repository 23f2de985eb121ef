#version 450
// Adaptive tone map, step 1 of the log-average luminance (Reinhard et al. 2002, Eq. 1:
// L_avg = exp(mean(log(delta + L_w)))): each invocation sums log(delta + L_w) over its
// TONEMAP_BLOCK^2 pixels, then the workgroup sums its invocations by a tree in shared memory
// and keeps the largest L_w, for adapt.comp to finish. Pixels outside the image add nothing.
#include "adaptive.glsl"
layout(local_size_x = TONEMAP_GROUP, local_size_y = TONEMAP_GROUP) in;
layout(push_constant) uniform Push { AdaptPush p; } push;
layout(set = 0, binding = TONEMAP_BINDING_HDR) uniform sampler2D hdr;
layout(set = 0, binding = TONEMAP_BINDING_PARTIALS, std430) buffer Partials { vec2 partials[]; };

const uint N = TONEMAP_GROUP * TONEMAP_GROUP;
shared float s_log[N];
shared float s_max[N];

void main() {
    uvec2 base = gl_GlobalInvocationID.xy * TONEMAP_BLOCK;
    uint i = gl_LocalInvocationIndex;
    float l = 0.0, m = 0.0;
    for (uint y = 0u; y < TONEMAP_BLOCK; ++y) {
        for (uint x = 0u; x < TONEMAP_BLOCK; ++x) {
            uvec2 p = base + uvec2(x, y);
            if (p.x >= push.p.size.x || p.y >= push.p.size.y) continue;
            vec3 c = tonemap_input(texelFetch(hdr, ivec2(p), 0).rgb);
            float Y = min(push.p.params2.z * tonemap_luminance(c), TONEMAP_MAX_LUMINANCE);
            l += log(push.p.params.y + Y);
            m = max(m, Y);
        }
    }
    s_log[i] = l;
    s_max[i] = m;
    barrier();
    for (uint stride = N / 2u; stride > 0u; stride /= 2u) {
        if (i < stride) {
            s_log[i] += s_log[i + stride];
            s_max[i] = max(s_max[i], s_max[i + stride]);
        }
        barrier();
    }
    if (i == 0u) partials[gl_WorkGroupID.y * gl_NumWorkGroups.x + gl_WorkGroupID.x] = vec2(s_log[0], s_max[0]);
}
