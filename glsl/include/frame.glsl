// Set 0, shared by every pass: frame uniforms, materials, environment, shadow maps.
#ifndef PRISM_FRAME_GLSL
#define PRISM_FRAME_GLSL
#include "common.glsl"

// FrameUniforms and GpuLight: src/shader_structs.rs (std140).
layout(set = 0, binding = BINDING_FRAME, std140) uniform FrameBlock { FrameUniforms frame; };

// A uniform buffer, not a storage buffer: lavapipe loads a storage buffer at a per-pixel
// index lane by lane (MAX_MATERIALS, src/shader_shared.rs).
layout(set = 0, binding = BINDING_MATERIALS, std140) uniform Materials {
    GpuMaterial materials[MAX_MATERIALS];
};

layout(set = 0, binding = BINDING_ENVIRONMENT) uniform sampler2D environment_map;
layout(set = 0, binding = BINDING_SHADOW_CUBE) uniform samplerCubeArray shadow_cubes;
layout(set = 0, binding = BINDING_SHADOW_2D) uniform sampler2DArray shadow_layers;
// Caustic-map atlas (Shah et al. 2007; src/technique/caustics/caustics_map.rs): flux per texel in W,
// laid out like the shadow atlas.
layout(set = 0, binding = BINDING_CAUSTIC_CUBE) uniform samplerCubeArray caustic_cubes;
layout(set = 0, binding = BINDING_CAUSTIC_2D) uniform sampler2DArray caustic_layers;
// The caustic map's receivers: distance from the light to the nearest diffuse receiver per
// caustic-map texel, stored like the shadow maps (glsl/shadow/shadow.frag).
layout(set = 0, binding = BINDING_CAUSTIC_RECEIVERS_CUBE) uniform samplerCubeArray caustic_receiver_cubes;
layout(set = 0, binding = BINDING_CAUSTIC_RECEIVERS_2D) uniform sampler2DArray caustic_receiver_layers;
// Photon-buffer caustic textures (Hu & Qin 2007 §3; src/technique/caustics/photon_buffer.rs): one layer
// per receiver rectangle, and the rectangles.
#include "photon_rect.glsl"
layout(set = 0, binding = BINDING_PHOTON_CAUSTICS) uniform sampler2DArray photon_caustics;
// A uniform buffer of MAX_NEARBY_RECTS receivers, read per pixel as the materials are.
layout(set = 0, binding = BINDING_PHOTON_RECTS, std140) uniform PhotonRects { GpuPhotonRect photon_rects[MAX_NEARBY_RECTS]; };

uint material_kind(uint m) { return kind_of(materials[m]); }

// The number of lights, and whether light l is a point light, from the specialisation
// constants where they are set (common.glsl), else from the frame's data.
uint light_count() { return LIGHT_COUNT == LIGHT_COUNT_ANY ? frame.info.x : LIGHT_COUNT; }
bool is_point_light(GpuLight l) {
    if (LIGHT_KINDS == LIGHT_KINDS_POINT) return true;
    if (LIGHT_KINDS == LIGHT_KINDS_DIRECTIONAL) return false;
    return uint(l.position.w + 0.5) == LIGHT_POINT;
}

// View-space direction through uv with z = -1 (pixel centre ((i+0.5)/W, (j+0.5)/H), j = 0
// the top row). Built from the projection's diagonal rather than by unprojecting a point:
// the near plane sits 1e-5 scene extents from the eye, and unprojecting a point there in
// world space loses most of the direction's precision to the camera's world position.
vec3 view_ray(vec2 uv) {
    vec2 ndc = uv * 2.0 - 1.0;
    return vec3(ndc.x / frame.proj[0][0], ndc.y / frame.proj[1][1], -1.0);
}

// Unit world-space direction of the camera ray through uv.
vec3 camera_ray(vec2 uv) {
    return normalize(mat3(frame.inv_view) * view_ray(uv));
}

// World-space position of the surface seen at uv with reversed depth d. For the infinite
// reversed-Z projection d = near / (-z_view), so the view-space distance along -z is near / d.
vec3 world_from_depth(vec2 uv, float d) {
    vec3 v = view_ray(uv) * (frame.clip.x / d);
    return (frame.inv_view * vec4(v, 1.0)).xyz;
}
#endif
