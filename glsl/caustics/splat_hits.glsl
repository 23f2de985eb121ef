// Caustics mapping (Shah et al. 2007, §III.C-F), the work of each grid vertex, done once: the
// vertex fetches the refractor textures, refracts (or reflects) the light direction,
// estimates where the ray meets the receivers from the receivers' positions map (§III.C
// Eq. 1-2 and §III.D Eq. 3-5), weighs its flux (§III.E Eq. 6-7), picks the caustic-atlas
// layer its hit lands in (a point light's cube face, §III.F "environment caustic map"; a
// directional light's one orthographic map) and sizes its Gaussian splat there. The splat
// pass (splat.vert) then only draws the records into their layers: the paper draws the grid
// once per map, and a cube's six faces would otherwise repeat every light path six times to
// keep one sixth of them. Vertices that see no specular surface, rays that are totally
// internally reflected, and rays whose receiver lookup finds nothing are dropped (layer -1),
// never written as NaN.
//
// Included by splat_hits.comp (the technique) and splat_hits_oracle.comp (ORACLE_TRACE
// defined: the analysis variant of render.caustics_map.oracle = "receiver"), which also binds
// the exact tracer's buffers in set 1 and replaces the receiver estimate by the exact hit.
#include "common.glsl"
#include "fresnel.glsl"

layout(local_size_x = REF_WORKGROUP) in;

layout(set = 0, binding = CAUSTIC_BINDING_FACES, std430) readonly buffer Faces { GpuCausticFace faces[]; };
layout(set = 0, binding = CAUSTIC_BINDING_MATERIALS, std430) readonly buffer Materials { GpuMaterial materials[]; };
layout(set = 0, binding = CAUSTIC_BINDING_RECEIVER_CUBE) uniform samplerCubeArray receiver_cubes;
layout(set = 0, binding = CAUSTIC_BINDING_RECEIVER_2D) uniform sampler2DArray receiver_layers;
layout(set = 0, binding = CAUSTIC_BINDING_FRONT_POSITION) uniform sampler2DArray front_position;
layout(set = 0, binding = CAUSTIC_BINDING_FRONT_NORMAL) uniform sampler2DArray front_normal;
layout(set = 0, binding = CAUSTIC_BINDING_BACK_POSITION) uniform sampler2DArray back_position;
layout(set = 0, binding = CAUSTIC_BINDING_BACK_NORMAL) uniform sampler2DArray back_normal;
// Eq. 6's V per source face: occlusion-query sample counts copied on the GPU.
layout(set = 0, binding = CAUSTIC_BINDING_VISIBLE, std430) readonly buffer Visible { uint visible[]; };
// Each atlas layer's world -> clip matrix (zero for a layer that is not drawn).
layout(set = 0, binding = CAUSTIC_BINDING_DESTINATIONS, std430) readonly buffer Destinations { mat4 destinations[]; };
layout(set = 0, binding = CAUSTIC_BINDING_SPLATS, std430) writeonly buffer Splats { GpuCausticSplat splats[]; };
// Each record that lands is counted in its layer, so that the splat pass neither draws nor
// clears a layer that no record reached, now or when it was last drawn.
layout(set = 0, binding = CAUSTIC_BINDING_COUNTS, std430) buffer Counts { uint counts[]; };
layout(constant_id = 0) const uint FLUX = FLUX_SOLID_ANGLE;
// render.caustics_map.exit: CAUSTIC_EXIT_WYMAN (the paper's, §IV) or CAUSTIC_EXIT_MARCH.
layout(constant_id = 1) const uint EXIT = CAUSTIC_EXIT_MARCH;
// render.caustics_map.splat: SPLAT_FIXED (§III.F) or SPLAT_FOOTPRINT, with its largest sigma.
layout(constant_id = 2) const uint SPLAT = SPLAT_FIXED;
layout(constant_id = 3) const float MAX_SIGMA = 8.0;
#include "light_path.glsl"

#ifdef ORACLE_TRACE
// The reference's own intersection code and buffers (glsl/reference/trace.glsl), in a set of
// their own: their REF_BINDING_* would meet the caustic bindings of set 0.
#define REF_SET 1
#include "../reference/trace.glsl"
#endif

layout(push_constant) uniform CausticHitsPushBlock { CausticHitsPush pc; };

// Cleared receiver distance ("no receiver in this direction"), FAR_DISTANCE in shadow_map.rs;
// bilinear filtering next to it still gives far more than any scene distance.
const float NO_RECEIVER = 1.0e30;

// The receivers' positions texture of §III.B step 1, stored as distances to the light (as
// the shadow maps are) and turned back into a position. Returns false where no receiver is
// seen. g = stored distance - x's own distance: zero exactly on the receiver (Theorem 1),
// positive in front of it, negative behind; the signed form gives true Newton-Raphson a
// derivative that does not vanish at the root and bisection a bracket.
bool receiver(GpuCausticFace f, vec3 x, out vec3 r, out float g) {
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

#ifdef ORACLE_TRACE
// The oracle of render.caustics_map.oracle = "receiver": the receiver estimate of §III.C
// (Eq. 1-2's iteration d' = |o - r(o + d dir)|, or the appendix's Newton-Raphson, Eq. 4-5,
// both on the receivers' positions map of §III.B step 1) replaced by the exact closest hit of
// the same ray o + t dir against the diffuse receivers (the reference's tracer). The ray
// passes through the specular objects, as the positions map leaves them out: o lies on the
// rasterized exit surface, which may lie just inside the tracer's exact sphere, and a
// reflected ray may meet another specular object. false where the ray meets no receiver
// (it leaves the scene). The grid, the exit point and direction (light_path, as
// render.caustics_map.exit says), the flux and the splat are the paper's: only the receiver
// estimate's error is removed, and its parameters (iterations, newton) no longer matter.
// With splat = "footprint" the neighbours' hits that size a splat (landing) are exact too.
bool intersect(GpuCausticFace f, vec3 o, vec3 dir, out vec3 hit) {
    hit = vec3(0.0);
    vec3 p = o;
    // A closed specular object is crossed in two hits; 8 allow for a concave one's folds
    // and a second object behind the first.
    for (int pass = 0; pass < 8; ++pass) {
        Hit h = trace(p, dir, 3.4e38);
        if (h.kind == 0u) return false;
        Surface s = surface_at(p, dir, h);
        if (kind_of(materials[s.material]) == MATERIAL_DIFFUSE) {
            hit = s.p;
            return true;
        }
        p = offset_origin(s, dir);
    }
    return false;
}
#else
// Where the ray o + d * dir meets the receivers (§III.C-D). The initial guess is the
// receiver seen from the light through o: the paper's d = 1 (Eq. 2) is in the units of its
// scene, while prism's scenes range from 1e-3 to 1e4 m.
bool intersect(GpuCausticFace f, vec3 o, vec3 dir, out vec3 hit) {
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
#endif

// Vulkan cube face (+X, -X, +Y, -Y, +Z, -Z) whose major axis holds v.
uint cube_face(vec3 v) {
    vec3 a = abs(v);
    if (a.x >= a.y && a.x >= a.z) return v.x >= 0.0 ? 0u : 1u;
    if (a.y >= a.z) return v.y >= 0.0 ? 2u : 3u;
    return v.z >= 0.0 ? 4u : 5u;
}

// Where the light through grid texel ij of face f lands on the receivers (no flux): for the
// footprint of a neighbouring vertex.
bool landing(GpuCausticFace f, int layer, ivec2 ij, int grid, int c, uint channels, out vec3 hit) {
    hit = vec3(0.0);
    if (any(lessThan(ij, ivec2(0))) || any(greaterThanEqual(ij, ivec2(grid)))) return false;
    vec3 origin, dir, weight, absorb;
    float cos_in;
    if (!light_path(f, layer, ij, grid, c, channels, EXIT, origin, dir, weight, absorb, cos_in)) return false;
    return intersect(f, origin, dir, hit);
}

// The splat's sigma in caustic-map texels. SPLAT_FIXED: the paper's fixed Gaussian (§III.F).
// SPLAT_FOOTPRINT (a departure): the beam around this vertex covers, on the receivers, about
// the area between its hit and its grid neighbours' hits; where refraction spreads the beam
// (a diverging lens such as the bunny's thin parts, or a grazing receiver) those hits are
// several texels apart and fixed splats leave the caustic as separate dots (§III.F: "the
// gaps between the point splats give a non-continuous appearance"). Half the larger spacing
// to the +i and +j neighbours (or -i, -j where those drop out) makes neighbouring Gaussians
// meet at 0.6 of their peak; clamped to [splat_sigma, max_splat_sigma] so that a neighbour
// across a silhouette or a fold of the caustic does not smear the whole map.
float splat_sigma(GpuCausticFace f, int layer, ivec2 ij, int grid, int c, uint channels, mat4 dest_view_proj,
                  vec2 centre) {
    float sigma = pc.params.x;
    if (SPLAT != SPLAT_FOOTPRINT) return sigma;
    float spacing = 0.0;
    for (int axis = 0; axis < 2; ++axis) {
        for (int side = 1; side >= -1; side -= 2) {
            ivec2 nij = ij;
            nij[axis] += side;
            vec3 hit;
            if (!landing(f, layer, nij, grid, c, channels, hit)) continue;
            vec4 clip = dest_view_proj * vec4(hit, 1.0);
            if (!(clip.w > 0.0)) continue;
            vec2 other = (clip.xy / clip.w * 0.5 + 0.5) * pc.params.w;
            spacing = max(spacing, distance(other, centre));
            break;   // one neighbour per axis: -1 only where +1 drops out
        }
    }
    return clamp(0.5 * spacing, sigma, MAX_SIGMA);
}

void main() {
    // Records are face-major, then texel, then channel, so that each light's records are
    // one range (its source faces are consecutive).
    uint index = gl_GlobalInvocationID.y * (gl_NumWorkGroups.x * gl_WorkGroupSize.x) + gl_GlobalInvocationID.x;
    uint channels = pc.face.y;
    uint per_face = pc.face.z;
    if (index >= pc.face.x * per_face * channels) return;
    splats[index].position = vec4(0.0, 0.0, 0.0, -1.0);
    splats[index].flux = vec4(0.0);
    int c = int(index % channels);
    uint s = index / channels / per_face;
    int texel = int(index / channels % per_face);
    GpuCausticFace f = faces[s];
    int grid = int(f.measure.z + 0.5);
    ivec2 ij = ivec2(texel % grid, texel / grid);
    int layer = int(s);
    vec3 origin, dir, weight, absorb_to_receiver;
    float cos_in;
    if (!light_path(f, layer, ij, grid, c, channels, EXIT, origin, dir, weight, absorb_to_receiver, cos_in)) return;
    vec3 flux;
    if (FLUX == FLUX_OCCLUSION_QUERY) {
        // Eq. 6: Phi_i = (N_i . L_i) / V of "the total flux through the surface of the
        // caustic-forming object visible to the light source", V the occlusion query's count
        // of rasterized pixels. That total, in W, is the light's flux through those V pixels,
        // V times a pixel's mean solid angle (or area): in physical units V cancels, and what
        // remains of Eq. 6 is the face's mean texel measure and the factor N . L.
        float v = float(visible[s]);
        if (!(v >= 1.0)) return;
        flux = f.intensity.rgb * (v * mean_texel_measure(f, grid)) * cos_in / v;
    } else {
        flux = f.intensity.rgb * texel_measure(f, ij, grid);
    }
    if (channels == 3u) {
        vec3 mask = vec3(0.0);
        mask[c] = 1.0;
        flux *= mask;
    }
    vec3 hit;
    if (!intersect(f, origin, dir, hit)) return;
    weight *= exp(-absorb_to_receiver * distance(origin, hit));
    flux *= weight;

    // Destination: a point light's caustic map is a cube, and each splat goes to the face
    // holding its direction (§III.F, "environment caustic map"); a directional light's is
    // the orthographic map of its shadow map. f.intensity.w is the light's first atlas layer.
    uint dest = uint(f.intensity.w + 0.5);
    if (uint(f.light.w + 0.5) == LIGHT_POINT) dest += cube_face(hit - f.light.xyz);
    mat4 dest_view_proj = destinations[dest];
    vec4 clip = dest_view_proj * vec4(hit, 1.0);
    // Behind the layer's eye, or a layer that is not drawn (zero matrix). Points outside its
    // clip volume are left to the rasterizer's clipping, as when the vertex shader did this.
    if (!(clip.w > 0.0) || any(isnan(flux)) || any(isinf(flux))) return;
    // Gaussian splat normalised over the texels the point covers: texel centres k + 0.5
    // within half the point size of the centre, separably in x and y.
    float n_map = pc.params.w;
    vec3 ndc = clip.xyz / clip.w;
    vec2 centre = (ndc.xy * 0.5 + 0.5) * n_map;
    float sigma = splat_sigma(f, layer, ij, grid, c, channels, dest_view_proj, centre);
    float size = 2.0 * ceil(3.0 * sigma) + 1.0;
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
    splats[index].position = vec4(ndc, float(dest));
    splats[index].flux = vec4(flux / max(sum.x * sum.y, 1e-12), sigma);
    atomicAdd(counts[dest], 1u);
}
