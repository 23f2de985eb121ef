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

#ifdef ORACLE_TRACE
// The reference's own intersection code and buffers (glsl/reference/trace.glsl), in a set of
// their own: their REF_BINDING_* would meet the G-buffer's and the impostors' in set 1.
#define REF_SET 2
#include "../reference/trace.glsl"
#endif

// Whether this draw shades pixel px: every pixel with a shared map; with one map per object
// (`render.impostor.maps = "per_object"`, §6) only the pixels of the map's own object.
bool impostor_owns(ivec2 px) {
    return pc.object.x == ALL_OBJECTS || uint(texelFetch(gbuf_albedo, px, 0).a + 0.5) == pc.object.x;
}

// Radiance arriving at world point p from unit direction R: Hit() in the environment
// impostor, then its radiance in the direction of the hit (§3: "looks up cube map envmap
// again to find illumination I of the hit point"); rays that leave the impostor see the
// environment.
#ifdef ORACLE_TRACE
// Whether the environment map leaves out `object` of material `mat`: a per-object map its own
// object, a shared map every object of the shading pass's kinds (IMPOSTOR_MAP_LEAVES_OUT, set
// by reflect.glsl and refract.glsl).
bool impostor_map_leaves_out(uint object, uint mat) {
    return pc.object.x == ALL_OBJECTS ? IMPOSTOR_MAP_LEAVES_OUT(material_kind(mat)) : object == pc.object.x;
}

// The oracle of render.impostor.oracle = "hit": the l of Hit(x, R) (§3; §2.1's d_p and Eq. 4's
// d_l, refined by Eq. 6, glsl/include/impostor.glsl) replaced by the exact hit of the same ray
// p + t R against the scene (the reference's closest hit), relative to o. The ray passes
// through the objects the map leaves out, as Hit() does: the surface it should find is the
// one the impostor stores. false where the ray meets nothing the map holds (it leaves the
// scene). The radiance is then looked up in the direction of that exact point, as the paper
// does for Hit()'s l, so only Hit()'s geometric error is removed: the map's resolution,
// filtering and its view-independent radiance from o remain.
bool oracle_hit(vec3 p, vec3 R, out vec3 l) {
    vec3 o = p;
    l = vec3(0.0);
    // A closed left-out object is crossed in two hits; 8 allow for a concave one's folds.
    for (int pass = 0; pass < 8; ++pass) {
        Hit h = trace(o, R, 3.4e38);
        if (h.kind == 0u) return false;
        Surface s = surface_at(o, R, h);
        uint object = object_of(h.kind, h.prim);
        if (!impostor_map_leaves_out(object, s.material)) {
            l = s.p - pc.env_reference.xyz;
            return true;
        }
        o = offset_origin(s, R);
    }
    return false;
}
#endif

vec3 localized_radiance(vec3 p, vec3 R) {
#ifdef ORACLE_TRACE
    vec3 l;
    if (!oracle_hit(p, R, l)) return environment(R);
#else
    vec3 l = impostor_hit(impostor_dist, DISTANCE_CHANNEL, p - pc.env_reference.xyz, R, ITERATIONS);
#endif
    if (dot(l, l) <= 0.0 || impostor_missed(impostor_dist, DISTANCE_CHANNEL, l)) return environment(R);
    return textureLod(impostor_radiance, l, 0.0).rgb;
}

// Reflectance of a mirror or conductor for cos_i = N.R.
vec3 metal_reflectance(GpuMaterial m, uint kind, float cos_i) {
    if (kind == MATERIAL_MIRROR) return m.spec_a.rgb;
    return FRESNEL_EXACT != 0u ? fresnel_conductor(cos_i, m.spec_a.rgb, m.spec_b.rgb)
                               : fresnel_conductor_approx(cos_i, m.spec_a.rgb, m.spec_b.rgb);
}
