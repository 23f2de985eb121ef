// Push constants of the impostor map passes (src/passes/distance_impostor.rs, MapPush).
layout(push_constant) uniform Push {
    mat4 view_proj;   // world -> clip space of one cube face
    vec4 reference;   // xyz: the map's reference point o
    uvec4 material;   // x: the draw's material index
} pc;
