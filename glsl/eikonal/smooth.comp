#version 450
// Gaussian pre-smoothing of the refractive-index field (Ihrke et al. 2007, section 5.1:
// "prior to gradient computation, we smooth the volumes ... standard deviation of typically
// 0.5 - 1.0 voxels"). Separable: one dispatch per axis. The field holds n - 1, so the air
// around the volume (n = 1) pads it with exact zeros.
#include "prism_shared.glsl"
layout(local_size_x = EIKONAL_GROUP, local_size_y = EIKONAL_GROUP, local_size_z = EIKONAL_GROUP) in;
layout(constant_id = 0) const uint AXIS = 0;
layout(constant_id = 1) const float SIGMA = 0.75;  // voxels; 0 copies the field
// Slices per index slab: a per-channel index (dispersion) stacks 3 slabs along z, and the
// blur never mixes two channels (each slab is padded by air on its own).
layout(constant_id = 2) const int SLAB = 1 << 30;
layout(set = 0, binding = EIKONAL_BINDING_SRC, r32f) uniform readonly image3D src;
layout(set = 0, binding = EIKONAL_BINDING_DST, r32f) uniform writeonly image3D dst;

void main() {
    ivec3 size = imageSize(src);
    ivec3 p = ivec3(gl_GlobalInvocationID);
    if (any(greaterThanEqual(p, size))) return;
    int radius = int(ceil(3.0 * SIGMA));
    ivec3 axis = ivec3(AXIS == 0u ? 1 : 0, AXIS == 1u ? 1 : 0, AXIS == 2u ? 1 : 0);
    float sum = 0.0, weights = 0.0;
    for (int k = -radius; k <= radius; ++k) {
        float w = SIGMA > 0.0 ? exp(-float(k * k) / (2.0 * SIGMA * SIGMA)) : 1.0;
        ivec3 q = p + k * axis;
        // Outside the box the deviation n - 1 is exactly 0 (air): it only adds weight.
        bool same_slab = q.z >= 0 && q.z / SLAB == p.z / SLAB;
        if (all(greaterThanEqual(q, ivec3(0))) && all(lessThan(q, size)) && same_slab) sum += w * imageLoad(src, q).r;
        weights += w;
    }
    imageStore(dst, p, vec4(sum / weights));
}
