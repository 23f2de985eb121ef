// After every run of the light simulator (all lights, channels and tiles): the additive
// accumulator of light_step.glsl's track-length estimate becomes the irradiance and
// direction volumes that single scattering (scatter.glsl, Eq. 6) and the receivers
// (light_receiver.frag, Eq. 7) sample. One invocation per voxel (workgroups of 4^3: a 1D
// dispatch of a 256^3 volume's 3 * 10^7 voxels would pass maxComputeWorkGroupCount).
#include "light_common.glsl"
layout(local_size_x = EIKONAL_GROUP, local_size_y = EIKONAL_GROUP, local_size_z = EIKONAL_GROUP) in;

float slab_value(ivec3 q, int comp) {
    float v = accum_value(q, comp);
    return isnan(v) || isinf(v) ? 0.0 : v;
}

void main() {
    ivec3 size = imageSize(irradiance);
    ivec3 q = ivec3(gl_GlobalInvocationID);
    if (any(greaterThanEqual(q, size))) return;
    // Rounding of a take-back (run.sign = -1) can leave tiny negative sums: clamp.
    vec3 e = max(vec3(slab_value(q, 0), slab_value(q, 1), slab_value(q, 2)), vec3(0.0));
    vec3 d = vec3(slab_value(q, 3), slab_value(q, 4), slab_value(q, 5));
    float s = e.r + e.g + e.b;
    imageStore(irradiance, q, vec4(e, s > 0.0 ? 1.0 : 0.0));
    imageStore(direction, q, s > 0.0 ? vec4(d, s) : vec4(0.0));
}
