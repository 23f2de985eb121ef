// The environment through the frame set, and its irradiance for diffuse surfaces.
#ifndef PRISM_ENVIRONMENT_GLSL
#define PRISM_ENVIRONMENT_GLSL
#include "frame.glsl"

vec3 environment(vec3 d) {
    return environment_lookup(environment_map, d);
}

// Irradiance E(n) from 9 SH coefficients L (Ramamoorthi & Hanrahan 2001, Eq. 13), in the
// order of src/frame/gpu_scene.rs's projection.
vec3 sh_irradiance(vec3 L[9], vec3 n) {
    const float c1 = 0.429043, c2 = 0.511664, c3 = 0.743125, c4 = 0.886227, c5 = 0.247708;
    vec3 L00 = L[0], L1m1 = L[1], L10 = L[2], L11 = L[3];
    vec3 L2m2 = L[4], L2m1 = L[5], L20 = L[6], L21 = L[7], L22 = L[8];
    float x = n.x, y = n.y, z = n.z;
    vec3 e = c1 * L22 * (x * x - y * y) + c3 * L20 * z * z + c4 * L00 - c5 * L20
           + 2.0 * c1 * (L2m2 * x * y + L21 * x * z + L2m1 * y * z)
           + 2.0 * c2 * (L11 * x + L1m1 * y + L10 * z);
    return max(e, vec3(0.0));
}

// The environment's irradiance on a surface of unit normal n.
vec3 environment_irradiance(vec3 n) {
    vec3 L[9];
    for (int k = 0; k < 9; ++k) L[k] = frame.env_sh[k].rgb;
    return sh_irradiance(L, n);
}
#endif
