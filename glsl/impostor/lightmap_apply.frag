#version 450
// Light-map caustics (Szirmay-Kalos et al. 2005, §5): each receiver reads its light map at
// its own (u, v) during deferred shading and adds the caustic irradiance times its diffuse
// BRDF (albedo / pi), blended additively onto the deferred result. One draw per receiver
// chart, of the chart's rectangle (impostor/lightmap_apply.vert): its pixels are those of its
// object index (G-buffer albedo.a); (u, v) follows from the world position through the
// receiver's planar chart, the same chart its uv-map texels hold.
#include "frame.glsl"
layout(set = 1, binding = BINDING_GBUF_NORMAL) uniform sampler2D gbuf_normal;
layout(set = 1, binding = BINDING_GBUF_ALBEDO) uniform sampler2D gbuf_albedo;
layout(set = 1, binding = BINDING_GBUF_DEPTH) uniform sampler2D gbuf_depth;
layout(set = 1, binding = BINDING_LIGHTMAPS) uniform sampler2DArray lightmaps;
layout(push_constant) uniform LightmapApplyPushBlock { LightmapApplyPush pc; };
layout(location = 0) out vec4 out_radiance;
void main() {
    ivec2 px = ivec2(gl_FragCoord.xy);
    // uv = (0, 0) at the top-left pixel corner, as the full-screen passes' in_uv.
    vec2 in_uv = gl_FragCoord.xy / frame.viewport.xy;
    float depth = texelFetch(gbuf_depth, px, 0).r;
    if (depth <= 0.0) discard;
    vec4 albedo = texelFetch(gbuf_albedo, px, 0);
    if (uint(albedo.a + 0.5) != uint(pc.edge_u.w + 0.5)) discard;
    vec4 nm = texelFetch(gbuf_normal, px, 0);
    if (material_kind(uint(nm.w + 0.5)) != MATERIAL_DIFFUSE) discard;
    // A box has one chart per face: the pixel belongs to the face whose outward normal
    // (e_u x e_v, src/scene/shapes.rs) it has; the G-buffer keeps the interpolated normal
    // unflipped, so opposite faces differ in sign.
    vec3 face_normal = cross(pc.edge_u.xyz, pc.edge_v.xyz);
    if (dot(nm.xyz, face_normal) < 0.7 * length(nm.xyz) * length(face_normal)) discard;
    vec3 p = world_from_depth(in_uv, depth);
    // The photons arrive on the receiver's side that faces the light (through or off the
    // specular objects between them): the side turned away from every light receives none,
    // though the chart, and so the light map, is the same for both sides of a surface.
    vec3 n = dot(nm.xyz, camera_ray(in_uv)) > 0.0 ? -nm.xyz : nm.xyz;
    bool lit_side = false;
    for (uint i = 0u; i < light_count(); ++i) {
        GpuLight l = frame.lights[i];
        vec3 wi = is_point_light(l) ? l.position.xyz - p : -l.position.xyz;
        lit_side = lit_side || dot(n, wi) > 0.0;
    }
    if (!lit_side) discard;
    vec3 d = p - pc.origin.xyz;
    vec2 uv = vec2(dot(d, pc.edge_u.xyz) / dot(pc.edge_u.xyz, pc.edge_u.xyz),
                   dot(d, pc.edge_v.xyz) / dot(pc.edge_v.xyz, pc.edge_v.xyz));
    if (any(lessThan(uv, vec2(-1e-3))) || any(greaterThan(uv, vec2(1.0 + 1e-3)))) discard;
    vec3 e = textureLod(lightmaps, vec3(uv, pc.origin.w), 0.0).rgb;
    out_radiance = vec4(finite_or_zero(e * albedo.rgb * (1.0 / PI)), 0.0);
}
