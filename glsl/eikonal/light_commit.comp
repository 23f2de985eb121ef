#version 450
// The paper's voxelization (Ihrke et al. 2007, section 5.2.2; render.eikonal.voxelization =
// "highest_energy"), second half: after a dispatch of the step kernel has raised each
// voxel's key to the highest energy of the rays that reached it (light_step.glsl), the
// patch whose key is still the voxel's writes its dE (Eq. 17) and its direction: "before we
// commit a patch to the 3D volume, we check if it is allowed to overwrite the one already
// stored there (if any), based on the highest energy criterion". Two rays of equal energy
// both write; either is the paper's answer.
#include "light_common.glsl"
layout(local_size_x = LIGHT_GROUP) in;

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= state.count) return;
    Patch p = src_patch(i);
    if (patch_mark(p) != run.substep + 1u) return;
    ivec3 q;
    vec3 dE;
    uint key;
    if (!voxel_sample(p, q, dE, key) || imageLoad(accum, accum_texel(q, 6)).x != key) return;
    vec3 dir = normalize(patch_dir(p));
    vec3 payload[2] = vec3[2](dE, dir);
    for (int k = 0; k < 6; ++k) {
        imageStore(accum, accum_texel(q, k), uvec4(floatBitsToUint(payload[k / 3][k % 3])));
    }
}
