#version 450
// The gradient of the smoothed index field by central differences (Ihrke et al. 2007,
// section 5.1: "the spatially varying refractive index field, as well as its gradient field
// are stored" in 3D textures). Writes (grad n per metre, n - 1); beyond the box n = 1.
#include "prism_shared.glsl"
layout(local_size_x = EIKONAL_GROUP, local_size_y = EIKONAL_GROUP, local_size_z = EIKONAL_GROUP) in;
// Voxel edge lengths in metres.
layout(constant_id = 0) const float VOXEL_X = 1.0;
layout(constant_id = 1) const float VOXEL_Y = 1.0;
layout(constant_id = 2) const float VOXEL_Z = 1.0;
// Slices per index slab (3 slabs stacked along z with dispersion; see smooth.comp).
layout(constant_id = 3) const int SLAB = 1 << 30;
layout(set = 0, binding = EIKONAL_BINDING_SRC, r32f) uniform readonly image3D src;
layout(set = 0, binding = EIKONAL_BINDING_DST, rgba32f) uniform writeonly image3D dst;

float deviation(ivec3 q, ivec3 size, int slab) {
    bool inside = all(greaterThanEqual(q, ivec3(0))) && all(lessThan(q, size)) && q.z / SLAB == slab;
    return inside ? imageLoad(src, q).r : 0.0;
}

void main() {
    ivec3 size = imageSize(src);
    ivec3 p = ivec3(gl_GlobalInvocationID);
    if (any(greaterThanEqual(p, size))) return;
    vec3 h = vec3(VOXEL_X, VOXEL_Y, VOXEL_Z);
    vec3 g;
    for (int a = 0; a < 3; ++a) {
        ivec3 e = ivec3(0);
        e[a] = 1;
        g[a] = (deviation(p + e, size, p.z / SLAB) - deviation(p - e, size, p.z / SLAB)) / (2.0 * h[a]);
    }
    imageStore(dst, p, vec4(g, deviation(p, size, p.z / SLAB)));
}
