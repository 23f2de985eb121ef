#version 450
// Caustics mapping (Shah et al. 2007, §III.C): one point per vertex of the refractor grid.
// The vertex fetches the refractor textures (vertex texture fetch), refracts (or reflects)
// the light direction, estimates where the ray meets the receivers from the receivers'
// positions map (§III.C Eq. 1-2 and §III.D Eq. 3-5), and is splatted there with its flux
// (§III.E Eq. 6-7). Vertices that see no specular surface, rays that are totally internally
// reflected, and rays whose receiver lookup finds nothing are dropped (placed outside the
// clip volume), never written as NaN.
#include "common.glsl"
#include "fresnel.glsl"

struct Face {
    mat4 view_proj;            // world -> source face clip space (the refractor textures)
    mat4 receiver_view_proj;   // directional: world -> the light's orthographic map
    vec4 light;                // xyz: position (point) or unit direction (directional); w: kind
    vec4 intensity;            // rgb: I in W/sr (point) or E in W/m^2 (directional); w: first atlas layer
    vec4 measure;              // x: face kind, y: tan(half angle) or half extent (m), z: grid size,
                               // w: largest chord of the specular objects (m)
    vec4 origin;               // directional: origin of the receivers' distance plane
};
layout(set = 0, binding = CAUSTIC_BINDING_FACES, std430) readonly buffer Faces { Face faces[]; };
layout(set = 0, binding = CAUSTIC_BINDING_MATERIALS, std430) readonly buffer Materials { Material materials[]; };
layout(set = 0, binding = CAUSTIC_BINDING_RECEIVER_CUBE) uniform samplerCubeArray receiver_cubes;
layout(set = 0, binding = CAUSTIC_BINDING_RECEIVER_2D) uniform sampler2DArray receiver_layers;
layout(set = 0, binding = CAUSTIC_BINDING_FRONT_POSITION) uniform sampler2DArray front_position;
layout(set = 0, binding = CAUSTIC_BINDING_FRONT_NORMAL) uniform sampler2DArray front_normal;
layout(set = 0, binding = CAUSTIC_BINDING_BACK_POSITION) uniform sampler2DArray back_position;
layout(set = 0, binding = CAUSTIC_BINDING_BACK_NORMAL) uniform sampler2DArray back_normal;

layout(push_constant) uniform Push {
    mat4 dest_view_proj;   // world -> destination caustic-map face clip space
    uvec4 face;            // x: first source face, y: source faces, z: destination cube face (6: 2D map), w: channels
    vec4 params;           // x: splat sigma (texels), y: iterations, z: NEWTON_*, w: map size (texels)
} pc;

layout(location = 0) flat out vec3 out_flux;
layout(location = 1) flat out vec3 out_splat;

// Cleared receiver distance ("no receiver in this direction"), FAR_DISTANCE in shadow_map.rs;
// bilinear filtering next to it still gives far more than any scene distance.
const float NO_RECEIVER = 1.0e30;

void drop_vertex() {
    gl_Position = vec4(2.0, 2.0, 2.0, 1.0);   // outside the clip volume: the point is culled
    gl_PointSize = 1.0;
    out_flux = vec3(0.0);
    out_splat = vec3(0.0);
}

// The receivers' positions texture of §III.B step 1, stored as distances to the light (as
// the shadow maps are) and turned back into a position. Returns false where no receiver is
// seen. g = stored distance - x's own distance: zero exactly on the receiver (Theorem 1),
// positive in front of it, negative behind; the signed form gives true Newton-Raphson a
// derivative that does not vanish at the root and bisection a bracket.
bool receiver(Face f, vec3 x, out vec3 r, out float g) {
    float layer = f.intensity.w;
    if (uint(f.light.w + 0.5) == LIGHT_POINT) {
        vec3 v = x - f.light.xyz;
        float dist = length(v);
        if (!(dist > 0.0)) return false;
        float stored = textureLod(receiver_cubes, vec4(v, layer / float(SHADOW_LAYERS_PER_LIGHT)), 0.0).r;
        if (!(stored < NO_RECEIVER)) return false;
        r = f.light.xyz + v * (stored / dist);
        g = stored - dist;
    } else {
        vec4 clip = f.receiver_view_proj * vec4(x, 1.0);
        vec2 uv = clip.xy * 0.5 + 0.5;
        if (any(lessThan(uv, vec2(0.0))) || any(greaterThan(uv, vec2(1.0)))) return false;
        float stored = textureLod(receiver_layers, vec3(uv, layer), 0.0).r;
        if (!(stored < NO_RECEIVER)) return false;
        float along = dot(x - f.origin.xyz, f.light.xyz);
        r = x + f.light.xyz * (stored - along);
        g = stored - along;
    }
    return true;
}

// Where the ray o + d * dir meets the receivers (§III.C-D). The initial guess is the
// receiver seen from the light through o: the paper's d = 1 (Eq. 2) is in the units of its
// scene, while prism's scenes range from 1e-3 to 1e4 m.
bool intersect(Face f, vec3 o, vec3 dir, out vec3 hit) {
    vec3 r;
    float g;
    if (!receiver(f, o, r, g)) return false;
    float d = distance(o, r);
    int iterations = int(pc.params.y + 0.5);
    if (uint(pc.params.z + 0.5) == NEWTON_APPROXIMATE) {
        // §III.C: the distance from the ray origin to the receiver point looked up at the
        // current estimate is the next estimate (Eq. 1 with d = d'); the answer is the
        // looked-up receiver point itself, as in EstimateIntersection.
        for (int k = 0; k < iterations; ++k) {
            if (!receiver(f, o + d * dir, r, g)) return false;
            d = distance(o, r);
        }
        hit = r;
        return true;
    }
    // The appendix's Newton-Raphson (Eq. 4) with the finite-difference derivative of Eq. 5,
    // on the signed g. The step eps is relative to the distance (the appendix's 0.1 is in
    // its scene's units). §III.D: NR may oscillate between two estimates; this is detected
    // by keeping the last two, and then (or when a step leaves the bracket [lo, hi] known
    // to hold the root, or the derivative vanishes) the step is a bisection instead.
    float eps = 1e-3 * max(d, 1e-20);
    float lo = 0.0, hi = -1.0;   // g > 0 at lo; hi < 0: no point behind a receiver seen yet
    float prev = -1.0;
    for (int k = 0; k < iterations; ++k) {
        float g0, g1;
        vec3 r1;
        if (!receiver(f, o + d * dir, r, g0)) return false;
        if (g0 >= 0.0) lo = max(lo, d); else hi = (hi < 0.0) ? d : min(hi, d);
        if (!receiver(f, o + (d + eps) * dir, r1, g1)) return false;
        float deriv = (g1 - g0) / eps;
        float next = d - g0 / deriv;
        bool oscillating = prev >= 0.0 && abs(next - prev) <= 1e-3 * d && abs(next - d) > 1e-3 * d;
        bool outside = !(next > lo) || (hi >= 0.0 && !(next < hi));
        if (oscillating || outside || isnan(next) || isinf(next)) {
            next = hi >= 0.0 ? 0.5 * (lo + hi) : 2.0 * max(d, lo);
        }
        prev = d;
        d = next;
    }
    if (!receiver(f, o + d * dir, r, g)) return false;
    hit = r;
    return true;
}

// The 2D texel of `f` that x projects to, or (-1, -1) outside the face.
ivec2 source_texel(Face f, vec3 x, int grid) {
    vec4 clip = f.view_proj * vec4(x, 1.0);
    if (!(clip.w > 0.0)) return ivec2(-1);
    vec2 t = (clip.xy / clip.w * 0.5 + 0.5) * float(grid);
    if (any(lessThan(t, vec2(0.0))) || any(greaterThanEqual(t, vec2(grid)))) return ivec2(-1);
    return ivec2(t);
}

// Whether x is still inside the object: in front of the back face the light sees at x's
// texel of source face f (distances from the light, or along a directional light).
bool inside(Face f, vec3 x, int grid, int layer) {
    ivec2 t = source_texel(f, x, grid);
    if (t.x < 0) return false;
    vec4 b = texelFetch(back_position, ivec3(t, layer), 0);
    if (b.w <= 0.0) return false;
    if (uint(f.light.w + 0.5) == LIGHT_POINT) {
        return distance(x, f.light.xyz) < distance(b.xyz, f.light.xyz);
    }
    return dot(x - b.xyz, f.light.xyz) < 0.0;
}

// Vulkan cube face (+X, -X, +Y, -Y, +Z, -Z) whose major axis holds v.
uint cube_face(vec3 v) {
    vec3 a = abs(v);
    if (a.x >= a.y && a.x >= a.z) return v.x >= 0.0 ? 0u : 1u;
    if (a.y >= a.z) return v.y >= 0.0 ? 2u : 3u;
    return v.z >= 0.0 ? 4u : 5u;
}

void main() {
    Face f0 = faces[pc.face.x];
    int grid = int(f0.measure.z + 0.5);
    int per_face = grid * grid;
    uint s = pc.face.x + uint(gl_VertexIndex / per_face);
    int texel = gl_VertexIndex % per_face;
    ivec2 ij = ivec2(texel % grid, texel / grid);
    Face f = faces[s];
    int layer = int(s);
    vec4 fp = texelFetch(front_position, ivec3(ij, layer), 0);
    if (fp.w <= 0.0) {
        drop_vertex();
        return;
    }
    vec4 fn = texelFetch(front_normal, ivec3(ij, layer), 0);
    vec3 p1 = fp.xyz;
    vec3 n1 = normalize(fn.xyz);
    bool point_light = uint(f.light.w + 0.5) == LIGHT_POINT;
    vec3 l = point_light ? normalize(p1 - f.light.xyz) : f.light.xyz;

    // The flux through this grid texel, in W: the light's intensity times the texel's solid
    // angle (perspective face), or its irradiance times the texel's area (orthographic).
    // This is Eq. 6 in physical units: the paper's weight 1/V is the texel's share of the
    // flux through the visible area of the object, here measured directly, so the total
    // does not depend on the grid resolution.
    vec2 ndc = (vec2(ij) + 0.5) / float(grid) * 2.0 - 1.0;
    float measure;
    if (uint(f.measure.x + 0.5) == CAUSTIC_FACE_PERSPECTIVE) {
        float t = f.measure.y;
        float q = 1.0 + t * t * dot(ndc, ndc);
        measure = (2.0 * t / float(grid)) * (2.0 * t / float(grid)) / (q * sqrt(q));
    } else {
        measure = (2.0 * f.measure.y / float(grid)) * (2.0 * f.measure.y / float(grid));
    }
    uint channels = pc.face.w;
    int c = gl_InstanceIndex;
    vec3 flux = f.intensity.rgb * measure;
    if (channels == 3u) {
        vec3 mask = vec3(0.0);
        mask[c] = 1.0;
        flux *= mask;
    }

    Material m = materials[uint(fn.w + 0.5)];
    uint kind = kind_of(m);
    float cos1 = clamp(dot(-l, n1), 0.0, 1.0);
    vec3 origin = p1;
    vec3 dir;
    vec3 weight;
    // Single-surface refraction (water): "attenuation is performed over the distance between
    // the surface and the receiver geometry" (§III.E).
    vec3 absorb_to_receiver = vec3(0.0);
    if (kind == MATERIAL_DIELECTRIC) {
        float ior = (channels == 3u) ? m.spec_a[c] : m.spec_a.x;
        dir = refract(l, n1, 1.0 / ior);
        weight = vec3(1.0 - fresnel_dielectric(cos1, 1.0 / ior));
        vec4 bp = texelFetch(back_position, ivec3(ij, layer), 0);
        if (bp.w > 0.0) {
            // Double-surface refraction (§IV): the exit point P2 where P1 + d T1 leaves the
            // object. The back faces seen from the light are a depth map, so the exit is the
            // root of the same signed function as the receiver's (Eq. 3): the back face's
            // distance from the light at the point's texel minus the point's own distance,
            // positive inside. The paper's derivative-free iteration (Eq. 1-2) converges
            // slowly near the silhouette, where T1 runs almost along the back surface, and
            // a wrong exit normal there turns into spurious total internal reflection; so
            // as Hu & Qin 2007 (§2.1) do for the exit, a linear search over the object's
            // largest chord brackets the first exit and a binary search refines it.
            float chord = f.measure.w;
            float lo = 0.0, hi = chord;
            const int MARCH = 16, BISECT = 10;
            bool found = false;
            for (int k = 1; k <= MARCH && !found; ++k) {
                float d = chord * float(k) / float(MARCH);
                if (!inside(f, p1 + d * dir, grid, layer)) {
                    hi = d;
                    found = true;
                } else {
                    lo = d;
                }
            }
            for (int k = 0; k < BISECT; ++k) {
                float mid = 0.5 * (lo + hi);
                if (inside(f, p1 + mid * dir, grid, layer)) lo = mid; else hi = mid;
            }
            float d = 0.5 * (lo + hi);
            vec3 exit_p = p1 + d * dir;
            ivec2 exit_t = source_texel(f, exit_p, grid);
            if (exit_t.x < 0 || texelFetch(back_position, ivec3(exit_t, layer), 0).w <= 0.0) {
                // Left through the silhouette: the back face at the last texel inside.
                exit_t = source_texel(f, p1 + lo * dir, grid);
                if (exit_t.x < 0) exit_t = ij;
            }
            vec3 n2 = normalize(texelFetch(back_normal, ivec3(exit_t, layer), 0).xyz);
            vec3 t2 = refract(dir, -n2, ior);
            if (dot(t2, t2) == 0.0) {
                // Total internal reflection: the light stays inside the object.
                drop_vertex();
                return;
            }
            weight *= 1.0 - fresnel_dielectric(clamp(dot(dir, n2), 0.0, 1.0), ior);
            // Beer-Lambert along the path inside the object (Eq. 7).
            weight *= exp(-m.spec_b.rgb * d);
            origin = exit_p;
            dir = t2;
        } else {
            absorb_to_receiver = m.spec_b.rgb;
        }
    } else if (kind == MATERIAL_MIRROR) {
        dir = reflect(l, n1);
        weight = m.spec_a.rgb;
    } else if (kind == MATERIAL_CONDUCTOR) {
        dir = reflect(l, n1);
        weight = fresnel_conductor(cos1, m.spec_a.rgb, m.spec_b.rgb);
    } else {
        drop_vertex();
        return;
    }
    if (dot(dir, dir) == 0.0) {
        drop_vertex();
        return;
    }
    dir = normalize(dir);
    vec3 hit;
    if (!intersect(f, origin, dir, hit)) {
        drop_vertex();
        return;
    }
    weight *= exp(-absorb_to_receiver * distance(origin, hit));
    flux *= weight;

    // Destination: a point light's caustic map is a cube, and each splat goes to the face
    // holding its direction (§III.F, "environment caustic map"); a directional light's is
    // the orthographic map of its shadow map.
    if (pc.face.z < 6u && cube_face(hit - f.light.xyz) != pc.face.z) {
        drop_vertex();
        return;
    }
    vec4 clip = pc.dest_view_proj * vec4(hit, 1.0);
    if (!(clip.w > 0.0) || any(isnan(flux)) || any(isinf(flux))) {
        drop_vertex();
        return;
    }
    // Gaussian splat normalised over the texels the point covers: texel centres k + 0.5
    // within half the point size of the centre, separably in x and y.
    float sigma = pc.params.x;
    float size = 2.0 * ceil(3.0 * sigma) + 1.0;
    float n_map = pc.params.w;
    vec2 centre = (clip.xy / clip.w * 0.5 + 0.5) * n_map;
    float k2 = 1.0 / (2.0 * sigma * sigma);
    vec2 sum = vec2(0.0);
    for (float k = floor(centre.x - 0.5 * size) - 1.0; k <= centre.x + 0.5 * size; k += 1.0) {
        float o = k + 0.5 - centre.x;
        if (abs(o) <= 0.5 * size) sum.x += exp(-o * o * k2);
    }
    for (float k = floor(centre.y - 0.5 * size) - 1.0; k <= centre.y + 0.5 * size; k += 1.0) {
        float o = k + 0.5 - centre.y;
        if (abs(o) <= 0.5 * size) sum.y += exp(-o * o * k2);
    }
    gl_Position = clip;
    gl_PointSize = size;
    out_flux = flux / max(sum.x * sum.y, 1e-12);
    out_splat = vec3(centre, k2);
}
