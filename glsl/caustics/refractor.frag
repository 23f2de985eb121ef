#version 450
// The refractor textures of caustics mapping (Shah et al. 2007, §III.B step 2), as MRT:
//   RT0 position: xyz world position, w > 0 where a specular surface is seen (0: cleared):
//                 front layer 1 + d_N (Wyman 2005 §3.1's distance along -N, interpolated from
//                 the vertices; 0 off the dielectrics and on open meshes), back layer 1
//   RT1 normal:   xyz unit normal,     w = material index
// CAUSTIC_LAYER_FRONT keeps the surface nearest the light, its normal turned toward the
// light (open shapes such as the ring and the water have no back to rely on).
// CAUSTIC_LAYER_BACK keeps the nearest surface facing away from the light: the exit
// surface of double-surface refraction ("rasterizing the back-faces of the object", §III.E),
// with its outward normal. Facing is decided by the interpolated normal, which holds for
// open meshes too; for a closed mesh with outward normals the pass also culls the faces the
// layer cannot keep (src/technique/caustics/caustics_map.rs, `RefractorLayers`).
#include "prism_shared.glsl"
layout(constant_id = 0) const uint MODE = CAUSTIC_LAYER_FRONT;
layout(push_constant) uniform RefractorPushBlock { RefractorPush pc; };
layout(location = 0) in vec3 in_position;
layout(location = 1) in vec3 in_normal;
layout(location = 2) in float in_d_n;
layout(location = 0) out vec4 out_position;
layout(location = 1) out vec4 out_normal;
void main() {
    vec3 l = uint(pc.light.w + 0.5) == LIGHT_POINT ? normalize(in_position - pc.light.xyz) : pc.light.xyz;
    vec3 n = normalize(in_normal);
    if (any(isnan(n))) n = -l;
    float facing = dot(n, l);
    if (MODE == CAUSTIC_LAYER_FRONT) {
        if (facing > 0.0) n = -n;
    } else if (facing <= 0.0) {
        discard;
    }
    out_position = vec4(in_position, MODE == CAUSTIC_LAYER_FRONT ? 1.0 + max(in_d_n, 0.0) : 1.0);
    out_normal = vec4(n, float(pc.info.x));
}
