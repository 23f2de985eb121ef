#version 450
// Second half of the highest-energy voxelization (Ihrke et al. 2007, section 5.2.2: "before
// we commit a patch to the 3D volume, we check if it is allowed to overwrite the one already
// stored there ... based on the highest energy criterion"): after every patch of the step
// has taken part in the atomicMax of light_step.comp, the patch whose key equals the
// voxel's maximum writes its irradiance and direction. Patches of equal keys write equal
// irradiance (to the largest channel); a later step only overwrites with a larger key.
#include "light_common.glsl"
layout(local_size_x = LIGHT_GROUP) in;

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= state.count) return;
    uvec2 d = deposits[i];
    if (d.x == 0xffffffffu || keys[d.x] != d.y) return;
    Patch p = src[i];
    ivec3 size = imageSize(irradiance);
    ivec3 q = ivec3(d.x % uint(size.x), (d.x / uint(size.x)) % uint(size.y), d.x / uint(size.x * size.y));
    float area = length(patch_normal(p));
    imageStore(irradiance, q, vec4(p.flux.rgb / area, 1.0));
    imageStore(direction, q, vec4(normalize(patch_dir(p)), 0.0));
}
