#version 450
// Whether the device's linear filter weighs two texels in full precision: the eikonal view
// renderer samples its smoothed index field (Ihrke et al. 2007, section 5.1: grad n and n at
// the voxel centres, trilinearly interpolated) with the device's filter where that gives the
// f32 interpolation of eight fetches (render.eikonal.hardware_filtering = "auto"). A GPU with
// 8-bit filter weights is off by up to 1/512 of the texels' difference; an f32 filter by
// rounding only. Texel 0 holds 0 and texel 1 holds 1, so the filtered value at a fraction f of
// the way between their centres is f itself.
#include "prism_shared.glsl"
layout(local_size_x = 64) in;
layout(set = 0, binding = BINDING_FILTER_PROBE_TEXELS) uniform sampler3D texels;
layout(std430, set = 0, binding = BINDING_FILTER_PROBE_ERRORS) buffer Errors { float errors[]; };

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= uint(errors.length())) return;
    // Fractions that no power of two divides evenly, so that coarse weights must round.
    float f = (float(i) + 0.31830989) / float(errors.length());
    float got = textureLod(texels, vec3(0.25 + 0.5 * f, 0.5, 0.5), 0.0).x;
    errors[i] = abs(got - f);
}
