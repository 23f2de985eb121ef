// The environment through the frame set, and its irradiance for diffuse surfaces.
#ifndef PRISM_ENVIRONMENT_GLSL
#define PRISM_ENVIRONMENT_GLSL
#include "frame.glsl"

vec3 environment(vec3 d) {
    return environment_lookup(environment_map, d);
}

// Irradiance E(n) from 9 SH coefficients (Ramamoorthi & Hanrahan 2001, Eq. 13).
vec3 environment_irradiance(vec3 n) {
    const float c1 = 0.429043, c2 = 0.511664, c3 = 0.743125, c4 = 0.886227, c5 = 0.247708;
    vec3 L00 = frame.env_sh[0].rgb, L1m1 = frame.env_sh[1].rgb, L10 = frame.env_sh[2].rgb, L11 = frame.env_sh[3].rgb;
    vec3 L2m2 = frame.env_sh[4].rgb, L2m1 = frame.env_sh[5].rgb, L20 = frame.env_sh[6].rgb, L21 = frame.env_sh[7].rgb;
    vec3 L22 = frame.env_sh[8].rgb;
    float x = n.x, y = n.y, z = n.z;
    vec3 e = c1 * L22 * (x * x - y * y) + c3 * L20 * z * z + c4 * L00 - c5 * L20
           + 2.0 * c1 * (L2m2 * x * y + L21 * x * z + L2m1 * y * z)
           + 2.0 * c2 * (L11 * x + L1m1 * y + L10 * z);
    return max(e, vec3(0.0));
}
#endif
