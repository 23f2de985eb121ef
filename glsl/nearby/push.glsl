// Push constants of the impostor-texture pass (src/technique/refraction/nearby_impostors.rs, ImpostorPush).
layout(push_constant) uniform Push {
    mat4 view_proj;   // world -> clip of glOrtho(-d_i, d_i, -d_i, d_i, near, far) from O_R to O_i
    vec4 origin;      // xyz: O_R, the refractor's centre
    vec4 axis;        // xyz: unit O_R -> O_i, the direction of projection
    uvec4 material;   // x: the object's material index, y: its layer, z: its own rectangle set (~0u: none)
    vec4 sphere;      // xyz: O_k, w: d_k (a dielectric's second interface)
} pc;
