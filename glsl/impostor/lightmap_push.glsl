// Push constants of the caustic-map pass of light-map caustics
// (src/technique/impostor/impostor_lightmap.rs, CausticPush).
layout(push_constant) uniform Push {
    mat4 view_proj;      // world -> the light's clip space (fitted to the specular objects)
    vec4 light;          // xyz: point light position or unit direction of travel; w: LIGHT_*
    vec4 intensity;      // rgb: I (W/sr, point) or E (W/m^2, directional); w: material index
    vec4 reference;      // xyz: reference point o of the uv map; w: tan(half angle) or half side (m)
    vec4 refractor;      // xyz: centre of the refractor map; w: caustic map size (texels)
} pc;
