// Hu & Qin 2007 §2.2: reflection and refraction of nearby geometry through impostor
// rectangles (src/technique/refraction/nearby_impostors.rs builds them), one rectangle set per OBJ_R,
// selected by nearby_set (nearby_select_object). nearby_radiance(P, Ray) is the
// "Ray Tracing Pass" of Fig. 13 with the seed selection of Fig. 17 and the iterative lookup
// of Fig. 16. The including shader declares, before including this file:
//   NEARBY_ITERATIONS (uint; 0 = the plain lookup of Fig. 13), NEARBY_TOLERANCE (float, a
//   fraction of d_i), NEARBY_SEEDS (uint), NEARBY_LOOKUP (NEARBY_LOOKUP_PAPER or
//   NEARBY_LOOKUP_NEAREST, render.hu_qin.nearby_lookup / recursive_lookup), and set-1
//   bindings BINDING_NEARBY_RECTS / BINDING_NEARBY_TEXTURE.
#ifndef PRISM_NEARBY_GLSL
#define PRISM_NEARBY_GLSL
#include "frame.glsl"
#include "environment.glsl"


// A uniform buffer, not a storage buffer: lavapipe loads a storage buffer at a per-pixel
// index lane by lane, a uniform buffer with one gather (docs/BENCHMARKS.md). Every set's
// rectangles fit: at most MAX_NEARBY_SETS of MAX_NEARBY_RECTS, 7.4 KiB in all.
layout(set = 1, binding = BINDING_NEARBY_RECTS, std140) uniform NearbyRects {
    GpuNearbyHeader nearby_header;
    GpuNearbyRect nearby_rects[MAX_NEARBY_SETS * MAX_NEARBY_RECTS];
};
// TEX_i (rgb: radiance) and TEX_DEPTH_i (a: axial distance dot(p - O_R, n_i)), layer i.
layout(set = 1, binding = BINDING_NEARBY_TEXTURE) uniform sampler2DArray nearby_tex;

// The rectangle set nearby_radiance looks up: that of OBJ_R, the object whose surface the ray
// leaves (§2.2.1: every reflector/refractor sees the others through its own rectangles). None
// (the environment only) by default.
const uint NEARBY_NO_SET = 0xffffffffu;
uint nearby_set = NEARBY_NO_SET;

bool nearby_has_set() {
    return nearby_set < min(nearby_header.info.y, MAX_NEARBY_SETS);
}

// Select the set whose OBJ_R is `object` (the G-buffer's albedo.a); false (environment
// only) when the object has none.
bool nearby_select_object(uint object) {
    nearby_set = NEARBY_NO_SET;
    for (uint s = 0u; s < min(nearby_header.info.y, MAX_NEARBY_SETS); ++s) {
        if (nearby_header.sets[s].z == object) {
            nearby_set = s;
            return true;
        }
    }
    return false;
}

// The functions below take RECT_k itself, loaded once by the caller: a CPU device (lavapipe)
// loads a storage buffer at a per-pixel index lane by lane, and each seed and correction step
// re-read the rectangle's 28 floats (docs/BENCHMARKS.md).

// Fig. 13's intersect() and UV(): the hit t > 0 of P + t Ray with RECT_k and its (u, v).
// Rays parallel to the plane (|cos| <= 1e-6) miss: no division by ~0. Mirrors
// NearbyRect::intersect (CPU, unit-tested).
bool nearby_rect_hit(GpuNearbyRect r, vec3 P, vec3 Ray, out float t, out vec2 uv) {
    t = 0.0;
    uv = vec2(0.0);
    float c = dot(Ray, r.axis.xyz);
    if (!(abs(c) > 1e-6)) return false;
    t = dot(r.center.xyz - P, r.axis.xyz) / c;
    if (!(t > 0.0)) return false;
    vec3 q = P + t * Ray - r.center.xyz;
    uv = vec2(dot(q, r.axis_u.xyz), dot(q, r.axis_v.xyz)) / (2.0 * r.center.w) + 0.5;
    return all(greaterThanEqual(uv, vec2(0.0))) && all(lessThanEqual(uv, vec2(1.0)));
}

// O_R of the selected set.
vec3 nearby_origin() {
    return nearby_header.origins[nearby_set].xyz;
}

// Fig. 16's projection of P_new into TEX_DEPTH_k: (u, v) of the parallel projection and the
// point's own depth z (axial distance from O_R, the same quantity the texture stores).
vec3 nearby_project(GpuNearbyRect r, vec3 origin, vec3 p) {
    vec4 clip = r.view_proj * vec4(p, 1.0);
    return vec3(clip.xy * 0.5 + 0.5, dot(p - origin, r.axis.xyz));
}

bool nearby_inside(vec2 uv) {
    return all(greaterThanEqual(uv, vec2(0.0))) && all(lessThanEqual(uv, vec2(1.0)));
}

// TEX_k at uv: rgb radiance, a depth (the far plane outside the texture).
vec4 nearby_texel(GpuNearbyRect r, vec2 uv) {
    if (!nearby_inside(uv)) return vec4(0.0, 0.0, 0.0, r.axis_u.w);
    return textureLod(nearby_tex, vec3(uv, r.axis_v.w), 0.0);
}

// A texel holds a surface when its depth is in front of the far plane it was cleared to.
bool nearby_covered(GpuNearbyRect r, vec4 texel) {
    return texel.a < r.axis_u.w - 1e-4 * r.center.w;
}

// Fig. 17's seed: P + alpha_j Ray, alpha_j = d_far (j + 1) / NEARBY_SEEDS. "The highest
// priority: the z-value of the initial point should be larger than the z-value of the
// corresponding P_select" (the point lies behind the surface seen from O_R): the first such
// alpha_j along the ray; otherwise the one whose z is closest to P_select's. P_rect itself is
// the last seed.
float nearby_seed(GpuNearbyRect r, vec3 origin, vec3 P, vec3 Ray, float t_rect) {
    float best = t_rect, best_err = 1e30;
    for (uint j = 0u; j < NEARBY_SEEDS; ++j) {
        float alpha = t_rect * float(j + 1u) / float(NEARBY_SEEDS);
        vec3 s = nearby_project(r, origin, P + alpha * Ray);
        vec4 texel = nearby_texel(r, s.xy);
        if (!nearby_covered(r, texel)) continue;
        float err = s.z - texel.a;
        if (err > 0.0) return alpha;
        if (-err < best_err) {
            best = alpha;
            best_err = -err;
        }
    }
    return best;
}

// The colour of RECT_k along the ray, found by Figs. 16-17 from the rectangle hit t_rect =
// d_far. False where the texel finally looked up is empty (the ray passes beside OBJ_k).
// `residual` is |depth - z| there (0 for the plain lookup), in world units.
bool nearby_lookup(GpuNearbyRect r, vec3 P, vec3 Ray, float t_rect, vec2 uv_rect, out vec3 color,
                   out float dist, out float residual) {
    vec3 origin = nearby_origin();
    float d_i = r.center.w;
    vec2 uv = uv_rect;
    dist = t_rect;
    residual = 0.0;
    if (NEARBY_ITERATIONS > 0u) {
        dist = nearby_seed(r, origin, P, Ray, t_rect);
        // Fig. 16: distance += (depth - z) / cos(theta), theta between Ray and the projection
        // direction. |cos| is kept >= 0.05 (rays grazing the rectangle: one step then moves at
        // most 20 depth differences instead of dividing by ~0), each step is bounded by the
        // object's size 2 d_i, and the point never goes behind P.
        float cos_t = dot(Ray, r.axis.xyz);
        cos_t = cos_t >= 0.0 ? max(cos_t, 0.05) : min(cos_t, -0.05);
        float tol = NEARBY_TOLERANCE * d_i;
        if (NEARBY_LOOKUP == NEARBY_LOOKUP_PAPER) {
            for (uint i = 0u; i < NEARBY_ITERATIONS; ++i) {
                vec3 s = nearby_project(r, origin, P + dist * Ray);
                float diff = nearby_texel(r, s.xy).a - s.z;
                residual = abs(diff);
                if (residual <= tol) break;
                dist = max(dist + clamp(diff / cos_t, -2.0 * d_i, 2.0 * d_i), 0.0);
            }
        } else {
            // prism's departure (render.hu_qin.nearby_lookup = "nearest"): the root of
            // f(t) = depth(t) - z(t) by secant steps. Fig. 16's step assumes the stored depth
            // constant along the ray (slope of f = -cos theta); the secant uses the slope
            // measured between the last two points, which is the surface's own where the ray
            // meets a tilted surface (the floor seen from the ball at a grazing angle), so
            // that the few iterations of §2.2.2 suffice there too. A step that lands on an
            // empty texel (beyond OBJ_k's silhouette, where the texture holds the far plane
            // and f jumps) is halved, up to 4 times, instead of being taken: a point past the
            // silhouette would otherwise end the lookup on the background texel.
            vec3 s = nearby_project(r, origin, P + dist * Ray);
            vec4 texel = nearby_texel(r, s.xy);
            float f = texel.a - s.z;
            float t_prev = dist, f_prev = f;
            bool have_prev = false;
            for (uint i = 0u; i < NEARBY_ITERATIONS; ++i) {
                if (abs(f) <= tol) break;
                float step = f / cos_t;
                if (have_prev && abs(f - f_prev) > 1e-6 * d_i) {
                    float secant = -f * (dist - t_prev) / (f - f_prev);
                    if (!isnan(secant) && !isinf(secant)) step = secant;
                }
                step = clamp(step, -2.0 * d_i, 2.0 * d_i);
                float t_next = max(dist + step, 0.0);
                vec3 s_next = nearby_project(r, origin, P + t_next * Ray);
                vec4 texel_next = nearby_texel(r, s_next.xy);
                for (uint h = 0u; h < 4u && !nearby_covered(r, texel_next) && nearby_covered(r, texel); ++h) {
                    t_next = 0.5 * (dist + t_next);
                    s_next = nearby_project(r, origin, P + t_next * Ray);
                    texel_next = nearby_texel(r, s_next.xy);
                }
                t_prev = dist;
                f_prev = f;
                have_prev = true;
                dist = t_next;
                texel = texel_next;
                f = texel.a - s_next.z;
            }
            residual = abs(f);
        }
        uv = nearby_project(r, origin, P + dist * Ray).xy;
    }
    vec4 texel = nearby_texel(r, uv);
    color = texel.rgb;
    return nearby_covered(r, texel);
}

// The surface the ray P + t Ray (unit) meets through the selected set's rectangles. False when
// no rectangle holds a surface along the ray.
// NEARBY_LOOKUP_PAPER: Fig. 13 picks the rectangle whose hit is closest to P. Where that
// texel is empty (the square is larger than the object's silhouette), the next-closest
// rectangle is tried instead of showing TEX_k's background.
// NEARBY_LOOKUP_NEAREST (prism's departure): every rectangle the ray meets is corrected
// (Figs. 16-17 with the secant steps above) and the nearest corrected surface along the ray
// is kept. Fig. 13's order is that of the rectangles, not of the surfaces: each rectangle
// faces O_R from behind its object, so a large object's rectangle lies far behind its
// nearest parts (sphere_nearby's back wall: its rectangle stands 2 m behind the wall), and
// rays towards the wall's foot meet the floor's rectangle first and show the floor beyond
// the wall. Candidates whose correction converged (residual within 4 texels' width: the
// nearest-sampled depth is a staircase, and a surface tilted up to ~75 degrees from the
// projection plane rises tan 75 < 4 texels' width across one texel) beat those that did not.
// A dielectric OBJ_k whose TEX_k refracts the environment only (no recursion level: §2.2.1's
// recursion truncated at level 0; bit k - first of the set's sets[].w) ranks after every other
// rectangle: its texel is the right surface but not what the glass shows, which is the scene
// behind it (transmission dominates at all but grazing incidence), displaced little by a slab
// or a thin tube and turned over by a ball lens; so the surface behind it is kept where a
// rectangle holds one. Counted on tests/recursion.rs's glass cube behind ball A at depth 0
// (docs/refraction.md): taking B's environment-only texel instead of the floor behind it cost
// more than the nearest surface gained everywhere else.
bool nearby_hit(vec3 P, vec3 Ray, out vec3 color, out float dist) {
    color = vec3(0.0);
    dist = 1e30;
    if (!nearby_has_set()) return false;
    uint first = nearby_header.sets[nearby_set].x;
    uint n = min(nearby_header.sets[nearby_set].y, MAX_NEARBY_RECTS);
    uint end = first + n;
    if (NEARBY_LOOKUP == NEARBY_LOOKUP_NEAREST) {
        float texel_width = 2.0 / float(textureSize(nearby_tex, 0).x);
        uint see_through = nearby_header.sets[nearby_set].w;
        bool found = false;
        // 2: a surface that is not an environment-only dielectric, + 1: converged.
        uint found_rank = 0u;
        for (uint i = first; i < end; ++i) {
            float t;
            vec2 uv;
            GpuNearbyRect r = nearby_rects[i];
            if (!nearby_rect_hit(r, P, Ray, t, uv)) continue;
            vec3 c;
            float d, residual;
            if (!nearby_lookup(r, P, Ray, t, uv, c, d, residual)) continue;
            bool converged = residual <= 4.0 * texel_width * r.center.w;
            uint rank = (((see_through >> (i - first)) & 1u) == 0u ? 2u : 0u) + (converged ? 1u : 0u);
            if (!found || rank > found_rank || (rank == found_rank && d < dist)) {
                color = c;
                dist = d;
                found = true;
                found_rank = rank;
            }
        }
        color = finite_or_zero(color);
        return found;
    }
    float last = -1.0;
    for (uint pass = 0u; pass < n; ++pass) {
        uint k = end;
        float t_k = 1e30;
        vec2 uv_k = vec2(0.0);
        for (uint i = first; i < end; ++i) {
            float t;
            vec2 uv;
            if (nearby_rect_hit(nearby_rects[i], P, Ray, t, uv) && t > last && t < t_k) {
                k = i;
                t_k = t;
                uv_k = uv;
            }
        }
        if (k == end) break;
        last = t_k;
        float residual;
        if (nearby_lookup(nearby_rects[k], P, Ray, t_k, uv_k, color, dist, residual)) {
            color = finite_or_zero(color);
            return true;
        }
    }
    return false;
}

// Radiance arriving at P from direction Ray (unit): nearby_hit, else the environment map
// ("If there is no rectangle intersected ... index into the environment map").
vec3 nearby_radiance(vec3 P, vec3 Ray) {
    vec3 color;
    float dist;
    return nearby_hit(P, Ray, color, dist) ? color : environment(Ray);
}
#endif
