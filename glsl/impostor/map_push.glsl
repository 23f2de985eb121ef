// Push constants of the impostor map passes (src/technique/impostor/distance_impostor.rs, MapPush).
layout(push_constant) uniform Push {
    mat4 view_proj;   // world -> clip space of one cube face
    vec4 reference;   // xyz: the map's reference point o
    uvec4 material;   // x: the draw's material index; y: uv map: light-map slot + 1 (0: no light map)
    vec4 chart_u;     // uv map: light-map u = dot(chart_u.xyz, p) + chart_u.w (p: world position)
    vec4 chart_v;     // uv map: light-map v = dot(chart_v.xyz, p) + chart_v.w
} pc;
