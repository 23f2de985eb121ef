// The exact tracer's view of the scene (src/reference/mod.rs builds these buffers): world-space
// vertices and BVH-ordered triangles, the BVH (src/reference/bvh.rs documents its layout), exact
// analytic spheres, the lights; then its intersection and specular-interaction code. Shared by
// the reference's compute passes (set 0, scene.glsl) and the raytrace technique's fragment pass
// (set 1, glsl/raytrace/raytrace.frag), so that both trace the same rays through the same
// arithmetic. The includer declares `materials[]` and `environment(d)` first, and REF_SET when
// the tracer's buffers are not in set 0.
#ifndef PRISM_REFERENCE_TRACE_GLSL
#define PRISM_REFERENCE_TRACE_GLSL
#include "common.glsl"
#include "fresnel.glsl"
#ifndef REF_SET
#define REF_SET 0
#endif


// A storage block, though every lane reads the same address: as a uniform block, lavapipe
// (Mesa 22.3) crashes ("stack smashing detected") compiling the raytrace technique's fragment
// pass, and water_pool's refraction_water pass took 10x as long.
layout(set = REF_SET, binding = REF_BINDING_UNIFORMS, std430) readonly buffer RefUniformsBlock { RefUniforms ref; };

// photon.w flags
const uint REF_FLAG_DISPERSION = 1u;   // some dielectric has an RGB ior: trace one channel per path
const uint REF_FLAG_JITTER = 2u;       // supersample the pixel area (default: pixel centres)


// The geometry, as texel buffers (src/reference/mod.rs, TraceGeometry): each lane of a
// traversal fetches a node or a triangle of its own, and a texel fetch gathers them in one
// instruction where lavapipe loads a storage buffer lane by lane. The texels are RGBA32UI,
// floats by their bits, so every value is the one the CPU wrote.
layout(set = REF_SET, binding = REF_BINDING_VERTICES) uniform usamplerBuffer vertex_texels;     // 2 per Vertex
layout(set = REF_SET, binding = REF_BINDING_TRIANGLES) uniform usamplerBuffer triangle_texels;  // i0, i1, i2, object
layout(set = REF_SET, binding = REF_BINDING_NODES) uniform usamplerBuffer node_texels;          // 2 per BvhNode
layout(set = REF_SET, binding = REF_BINDING_SPHERES) uniform usamplerBuffer sphere_texels;      // 2 per GpuSphere
layout(set = REF_SET, binding = REF_BINDING_OBJECTS) uniform usamplerBuffer object_texels;      // R32UI: material

uvec4 triangle_at(uint k) { return texelFetch(triangle_texels, int(k)); }
// The object a hit belongs to.
uint object_of(uint kind, uint prim) {
    return kind == 2u ? texelFetch(sphere_texels, int(2u * prim + 1u)).x : triangle_at(prim).w;
}
uint object_material(uint object) { return texelFetch(object_texels, int(object)).x; }
vec4 sphere_center_radius(uint s) { return uintBitsToFloat(texelFetch(sphere_texels, int(2u * s))); }

// ---------------------------------------------------------------------------------------
// Random numbers: a PCG hash per (pixel or photon, iteration, seed), then an LCG stream.
// Deterministic given the seed.
uint pcg_hash(uint v) {
    uint state = v * 747796405u + 2891336453u;
    uint word = ((state >> ((state >> 28u) + 4u)) ^ state) * 277803737u;
    return (word >> 22u) ^ word;
}
uint rng_init(uint index, uint iteration, uint seed) {
    return pcg_hash(index ^ pcg_hash(iteration ^ pcg_hash(seed)));
}
float rand(inout uint state) {
    state = state * 747796405u + 2891336453u;
    return float(pcg_hash(state) >> 8) * (1.0 / 16777216.0);
}

// ---------------------------------------------------------------------------------------
// Intersection. Möller-Trumbore, the same arithmetic as bvh::intersect_triangle on the CPU.
// A Vertex is eight floats: position.xyz normal.x | normal.yz checker_uv.
vec3 vertex_position(uint i) { return uintBitsToFloat(texelFetch(vertex_texels, int(2u * i)).xyz); }
vec3 vertex_normal(uint i) {
    return uintBitsToFloat(uvec3(texelFetch(vertex_texels, int(2u * i)).w, texelFetch(vertex_texels, int(2u * i + 1u)).xy));
}
vec2 vertex_uv(uint i) { return uintBitsToFloat(texelFetch(vertex_texels, int(2u * i + 1u)).zw); }

// Any hit with t > 0; callers decide which hit wins.
bool intersect_triangle(vec3 o, vec3 d, vec3 a, vec3 b, vec3 c, out float t, out vec2 uv) {
    vec3 e1 = b - a, e2 = c - a;
    vec3 p = cross(d, e2);
    float det = dot(e1, p);
    t = 0.0; uv = vec2(0.0);
    if (abs(det) < 1e-30) return false;
    float inv = 1.0 / det;
    vec3 s = o - a;
    float u = dot(s, p) * inv;
    if (u < 0.0 || u > 1.0) return false;
    vec3 q = cross(s, e1);
    float v = dot(d, q) * inv;
    if (v < 0.0 || u + v > 1.0) return false;
    t = dot(e2, q) * inv;
    uv = vec2(u, v);
    return t > 0.0;
}

// The hit rule shared with bvh.rs: closer, or equally close with a lower triangle index.
bool better(float t, uint k, float best_t, uint best_k, bool have) {
    return t < best_t || (have && t == best_t && k < best_k);
}

// Exact ray/sphere intersection; the nearest root beyond t_min. Uses the numerically
// stable form of the quadratic (no cancellation for distant spheres or grazing rays).
bool intersect_sphere(vec3 o, vec3 d, vec4 s, float t_min, float t_max, out float t) {
    vec3 oc = o - s.xyz;
    float b = dot(oc, d);
    // c computed as |oc|^2 - r^2 via (|oc| - r)(|oc| + r) keeps precision for huge scenes.
    float loc = length(oc);
    float c = (loc - s.w) * (loc + s.w);
    vec3 perp = oc - b * d;
    float disc = s.w * s.w - dot(perp, perp);   // = b^2 - c, without cancellation
    t = 0.0;
    if (disc < 0.0) return false;
    float sq = sqrt(disc);
    float q = -b - sign(b) * sq;
    if (b == 0.0) q = sq;
    float t0 = q, t1 = (q != 0.0) ? c / q : 0.0;
    if (t0 > t1) { float tmp = t0; t0 = t1; t1 = tmp; }
    if (t0 > t_min && t0 < t_max) { t = t0; return true; }
    if (t1 > t_min && t1 < t_max) { t = t1; return true; }
    return false;
}

bool slab(vec3 o, vec3 inv_d, vec3 lo, vec3 hi, float t_max) {
    vec3 t0 = (lo - o) * inv_d, t1 = (hi - o) * inv_d;
    vec3 tn = min(t0, t1), tf = max(t0, t1);
    float near = max(max(tn.x, tn.y), max(tn.z, 0.0));
    float far = min(min(tf.x, tf.y), min(tf.z, t_max));
    return near <= far;
}

struct Hit {
    float t;
    uint prim;     // triangle index (BVH order) or sphere index
    uint kind;     // 0: none, 1: triangle, 2: sphere
    vec2 uv;       // triangle barycentrics
};

// Closest triangle by BVH traversal. Ties go to the lower triangle index, as in brute force.
// The threaded layout (src/reference/bvh.rs) needs no stack: into a node's subtree where the
// ray meets its box, past it where not.
Hit trace_triangles(vec3 o, vec3 d, float t_max) {
    Hit h; h.t = t_max; h.prim = 0u; h.kind = 0u; h.uv = vec2(0.0);
    if (ref.counts.x == 0u) return h;
    vec3 inv_d = 1.0 / d;
    uint nodes = ref.counts.y;
    for (uint i = 0u; i < nodes;) {
        uvec4 lo_index = texelFetch(node_texels, int(2u * i)), hi_count = texelFetch(node_texels, int(2u * i + 1u));
        bool hit = slab(o, inv_d, uintBitsToFloat(lo_index.xyz), uintBitsToFloat(hi_count.xyz), h.t);
        uint count = hi_count.w;
        uint index = lo_index.w;
        bool leaf = count > 0u;
        i = hit || leaf ? i + 1u : index;
        if (hit && leaf) {
            for (uint k = index; k < index + count; ++k) {
                uvec4 tri = triangle_at(k);
                float t; vec2 uv;
                if (intersect_triangle(o, d, vertex_position(tri.x), vertex_position(tri.y), vertex_position(tri.z), t, uv)
                    && better(t, k, h.t, h.prim, h.kind == 1u)) {
                    h.t = t; h.prim = k; h.kind = 1u; h.uv = uv;
                }
            }
        }
    }
    return h;
}

// Closest triangle by testing all: the ground truth for the BVH test.
Hit trace_triangles_brute_force(vec3 o, vec3 d, float t_max) {
    Hit h; h.t = t_max; h.prim = 0u; h.kind = 0u; h.uv = vec2(0.0);
    for (uint k = 0u; k < ref.counts.x; ++k) {
        uvec4 tri = triangle_at(k);
        float t; vec2 uv;
        if (intersect_triangle(o, d, vertex_position(tri.x), vertex_position(tri.y), vertex_position(tri.z), t, uv)
            && better(t, k, h.t, h.prim, h.kind == 1u)) {
            h.t = t; h.prim = k; h.kind = 1u; h.uv = uv;
        }
    }
    return h;
}

Hit trace(vec3 o, vec3 d, float t_max) {
    Hit h = trace_triangles(o, d, t_max);
    for (uint s = 0u; s < ref.dims.w; ++s) {
        float t;
        if (intersect_sphere(o, d, sphere_center_radius(s), 0.0, h.t, t)) {
            h.t = t; h.prim = s; h.kind = 2u;
        }
    }
    return h;
}

// Anything between o and o + t_max d? (Shadow rays.)
bool occluded(vec3 o, vec3 d, float t_max) {
    return trace(o, d, t_max).kind != 0u;
}

// ---------------------------------------------------------------------------------------
// Surface at a hit.
struct Surface {
    vec3 p;        // position
    vec3 ng;       // unit geometric normal, on the same side as the shading normal
    vec3 ns;       // unit shading normal (interpolated; the geometric one if degenerate)
    vec2 st;       // checker coordinates
    uint material;
};

Surface surface_at(vec3 o, vec3 d, Hit h) {
    Surface s;
    if (h.kind == 2u) {
        s.p = o + h.t * d;
        s.ng = normalize(s.p - sphere_center_radius(h.prim).xyz);
        s.ns = s.ng;
        s.st = s.p.xz;
        s.material = object_material(object_of(h.kind, h.prim));
        return s;
    }
    uvec4 tri = triangle_at(h.prim);
    vec3 a = vertex_position(tri.x), b = vertex_position(tri.y), c = vertex_position(tri.z);
    float w = 1.0 - h.uv.x - h.uv.y;
    // Barycentric position: more precise than o + t d far from the origin.
    s.p = w * a + h.uv.x * b + h.uv.y * c;
    vec3 n = w * vertex_normal(tri.x) + h.uv.x * vertex_normal(tri.y) + h.uv.y * vertex_normal(tri.z);
    vec3 g = cross(b - a, c - a);
    float gl = length(g);
    float nl = length(n);
    s.ns = nl > 1e-30 ? n / nl : (gl > 0.0 ? g / gl : -d);
    s.ng = gl > 0.0 ? g / gl : s.ns;
    if (dot(s.ng, s.ns) < 0.0) s.ng = -s.ng;
    s.st = w * vertex_uv(tri.x) + h.uv.x * vertex_uv(tri.y) + h.uv.y * vertex_uv(tri.z);
    s.material = object_material(tri.w);
    return s;
}

// Offset a ray origin off a surface along the geometric normal, towards side `dir`.
vec3 offset_origin(Surface s, vec3 dir) {
    float eps = ref.proj.z * (1.0 + max(max(abs(s.p.x), abs(s.p.y)), abs(s.p.z)) / max(ref.proj.w, 1e-30));
    return s.p + s.ng * (dot(dir, s.ng) >= 0.0 ? eps : -eps);
}

// ---------------------------------------------------------------------------------------
// One specular interaction at a mirror, conductor or dielectric, and its two branches.
struct Interaction {
    // Common to both branches: a mirror's reflectance, a conductor's Fresnel term, or at a
    // dielectric the Beer-Lambert absorption exp(-sigma_a d) of the segment just travelled
    // inside it (dielectrics are not nested: entering goes from vacuum into the material,
    // exiting from the material into vacuum).
    vec3 weight;
    float F;             // exact dielectric Fresnel reflectance (metals reflect only)
    bool transmits;      // a dielectric without total internal reflection
    vec3 reflected;      // unit directions
    vec3 refracted;
    float scale;         // (n_i/n_t)^2 on transmission when radiance_scale, else 1
};

// `channel` is the wavelength channel traced (0..2) or -1 when the ior is the same for all.
// `radiance_scale`: camera and gathering paths carry radiance, scaled by (n_i/n_t)^2 on
// transmission; photons carry flux and pass false. Returns false at a diffuse surface.
bool interaction_at(Surface s, vec3 d, float t_segment, int channel, bool radiance_scale, out Interaction x) {
    GpuMaterial m = materials[s.material];
    uint kind = kind_of(m);
    bool exiting = dot(d, s.ng) > 0.0;
    vec3 n = exiting ? -s.ns : s.ns;              // shading normal facing the incoming ray
    float cos_i = clamp(-dot(d, n), 0.0, 1.0);
    x.weight = vec3(1.0);
    x.F = 1.0;
    x.transmits = false;
    x.reflected = reflect(d, n);
    x.refracted = vec3(0.0);
    x.scale = 1.0;
    if (kind == MATERIAL_MIRROR || kind == MATERIAL_CONDUCTOR) {
        x.weight = kind == MATERIAL_MIRROR ? m.spec_a.rgb : fresnel_conductor(cos_i, m.spec_a.rgb, m.spec_b.rgb);
        return true;
    }
    if (kind != MATERIAL_DIELECTRIC) return false;
    if (exiting) x.weight = exp(-m.spec_b.rgb * t_segment);
    float ior = channel < 0 ? m.spec_a.r : m.spec_a[channel];
    ior = max(ior, 1e-6);
    float n_i = exiting ? ior : 1.0, n_t = exiting ? 1.0 : ior;
    float eta = n_i / n_t;
    x.F = fresnel_dielectric(cos_i, eta);
    vec3 t_dir = refract(d, n, eta);
    x.transmits = dot(t_dir, t_dir) != 0.0;
    if (x.transmits) x.refracted = normalize(t_dir);
    if (radiance_scale) x.scale = (n_i * n_i) / (n_t * n_t);
    return true;
}

// One specular interaction choosing reflection with probability F at dielectrics (exact
// Fresnel; unbiased with weight 1). Returns false if the path ends.
// `u` >= 2 forces transmission wherever it is possible (deterministic test paths).
bool specular_step(Surface s, inout vec3 o, inout vec3 d, inout vec3 beta, float t_segment, int channel,
                   float u, bool radiance_scale) {
    Interaction x;
    if (!interaction_at(s, d, t_segment, channel, radiance_scale, x)) return false;
    beta *= x.weight;
    if (!x.transmits || u < x.F) {
        d = x.reflected;
    } else {
        d = x.refracted;
        beta *= x.scale;
    }
    o = offset_origin(s, d);
    return true;
}

// An orthonormal basis around unit n (Duff et al. 2017, "Building an orthonormal basis,
// revisited").
void basis(vec3 n, out vec3 t, out vec3 b) {
    float s = n.z >= 0.0 ? 1.0 : -1.0;
    float a = -1.0 / (s + n.z);
    float c = n.x * n.y * a;
    t = vec3(1.0 + s * n.x * n.x * a, s * c, -s * n.x);
    b = vec3(c, s + n.y * n.y * a, -n.y);
}

vec3 cosine_sample(vec3 n, inout uint rng) {
    float r = sqrt(rand(rng)), phi = 2.0 * PI * rand(rng);
    vec3 t, b;
    basis(n, t, b);
    return normalize(r * cos(phi) * t + r * sin(phi) * b + sqrt(max(0.0, 1.0 - r * r)) * n);
}
#endif
