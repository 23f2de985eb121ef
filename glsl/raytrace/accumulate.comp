#version 450
// The raytrace technique's running mean (src/technique/raytrace.rs, render.raytrace.accumulate):
// the frame's HDR image, as the last raytrace pass left it, blended into the mean of the
// frames since the last change, which then replaces the frame's HDR image for what follows
// (the tone map). With push.frames = n frames before this one, the mean of n + 1 frames is
//   m_{n+1} = m_n + (x - m_n) / (n + 1),
// the incremental form, whose rounding stays at a few ulps of the values instead of growing
// with a running sum. A pixel that is the same in every frame (everything but the photons'
// caustic) stays bit for bit what it is: x - m_n = 0.
#include "prism_shared.glsl"
layout(local_size_x = WORKGROUP_2D, local_size_y = WORKGROUP_2D) in;

layout(set = 0, binding = ACCUMULATE_BINDING_HDR, rgba32f) uniform image2D hdr;
layout(set = 0, binding = ACCUMULATE_BINDING_MEAN, rgba32f) uniform image2D mean;
layout(push_constant) uniform AccumulatePushBlock { AccumulatePush push; };

void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    if (p.x >= int(push.width) || p.y >= int(push.height)) {
        return;
    }
    vec4 x = imageLoad(hdr, p);
    vec4 m;
    if (push.frames == 0u) {
        // The first frame since a change: itself, whatever the mean held (undefined after
        // the image was made).
        m = x;
    } else if (push.frames >= push.limit) {
        // The limit reached: the mean of the first `limit` frames, held.
        m = imageLoad(mean, p);
    } else {
        vec4 a = imageLoad(mean, p);
        m = a + (x - a) / float(push.frames + 1u);
    }
    imageStore(mean, p, m);
    imageStore(hdr, p, m);
}
