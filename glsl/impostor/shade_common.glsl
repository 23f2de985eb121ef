// Set 1 and push constants of the impostor shading passes (src/technique/impostor/distance_impostor.rs,
// ShadePush), and the localized environment lookup of §3.
#include "frame.glsl"
#include "environment.glsl"
#include "fresnel.glsl"
#include "impostor.glsl"
// 0: Hit() iterations (`render.impostor.iterations`).
layout(constant_id = 0) const uint ITERATIONS = 4;
// 1: channel of the distance: 3 = alpha of the radiance cube, 0 = separate distance cube.
layout(constant_id = 1) const uint DISTANCE_CHANNEL = 3;
// 2: conductor Fresnel: 0 = the paper's approximation, 1 = exact.
layout(constant_id = 2) const uint FRESNEL_EXACT = 0;
layout(set = 1, binding = BINDING_GBUF_NORMAL) uniform sampler2D gbuf_normal;
layout(set = 1, binding = BINDING_GBUF_DEPTH) uniform sampler2D gbuf_depth;
// a: object index (glsl/gbuffer/gbuffer.frag).
layout(set = 1, binding = BINDING_GBUF_ALBEDO) uniform sampler2D gbuf_albedo;
layout(set = 1, binding = BINDING_IMPOSTOR_RADIANCE) uniform samplerCube impostor_radiance;
// The radiance cube itself unless the distance is separate (DISTANCE_CHANNEL picks).
layout(set = 1, binding = BINDING_IMPOSTOR_DISTANCE) uniform samplerCube impostor_dist;
layout(push_constant) uniform ShadePushBlock { ShadePush pc; };

const uint ALL_OBJECTS = 0xffffffffu;

// Whether this draw shades pixel px: every pixel with a shared map; with one map per object
// (`render.impostor.maps = "per_object"`, §6) only the pixels of the map's own object.
bool impostor_owns(ivec2 px) {
    return pc.object.x == ALL_OBJECTS || uint(texelFetch(gbuf_albedo, px, 0).a + 0.5) == pc.object.x;
}

// Radiance arriving at world point p from unit direction R: Hit() in the environment
// impostor, then its radiance in the direction of the hit (§3: "looks up cube map envmap
// again to find illumination I of the hit point"); rays that leave the impostor see the
// environment.
vec3 localized_radiance(vec3 p, vec3 R) {
    vec3 x = p - pc.env_reference.xyz;
    vec3 l = impostor_hit(impostor_dist, DISTANCE_CHANNEL, x, R, ITERATIONS);
    if (dot(l, l) <= 0.0 || impostor_missed(impostor_dist, DISTANCE_CHANNEL, l)) return environment(R);
    return textureLod(impostor_radiance, l, 0.0).rgb;
}

// Reflectance of a mirror or conductor for cos_i = N.R.
vec3 metal_reflectance(GpuMaterial m, uint kind, float cos_i) {
    if (kind == MATERIAL_MIRROR) return m.spec_a.rgb;
    return FRESNEL_EXACT != 0u ? fresnel_conductor(cos_i, m.spec_a.rgb, m.spec_b.rgb)
                               : fresnel_conductor_approx(cos_i, m.spec_a.rgb, m.spec_b.rgb);
}
