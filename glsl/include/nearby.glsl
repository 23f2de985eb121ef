// Hu & Qin 2007 §2.2: reflection and refraction of nearby geometry through impostor
// rectangles (src/technique/refraction/nearby_impostors.rs builds them), one rectangle set per OBJ_R,
// selected by nearby_set (nearby_select_object). nearby_radiance(P, Ray) is the
// "Ray Tracing Pass" of Fig. 13 with the seed selection of Fig. 17 and the iterative lookup
// of Fig. 16. The including shader declares, before including this file:
//   NEARBY_ITERATIONS (uint; 0 = the plain lookup of Fig. 13), NEARBY_TOLERANCE (float, a
//   fraction of d_i), NEARBY_SEEDS (uint), and set-1 bindings BINDING_NEARBY_RECTS /
//   BINDING_NEARBY_TEXTURE.
#ifndef PRISM_NEARBY_GLSL
#define PRISM_NEARBY_GLSL
#include "frame.glsl"
#include "environment.glsl"


layout(set = 1, binding = BINDING_NEARBY_RECTS, std430) readonly buffer NearbyRects {
    GpuNearbyHeader nearby_header;
    GpuNearbyRect nearby_rects[];
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

// Fig. 13's intersect() and UV(): the hit t > 0 of P + t Ray with RECT_k and its (u, v).
// Rays parallel to the plane (|cos| <= 1e-6) miss: no division by ~0. Mirrors
// NearbyRect::intersect (CPU, unit-tested).
bool nearby_rect_hit(uint k, vec3 P, vec3 Ray, out float t, out vec2 uv) {
    GpuNearbyRect r = nearby_rects[k];
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

// Fig. 16's projection of P_new into TEX_DEPTH_k: (u, v) of the parallel projection and the
// point's own depth z (axial distance from O_R, the same quantity the texture stores).
vec3 nearby_project(uint k, vec3 p) {
    vec4 clip = nearby_rects[k].view_proj * vec4(p, 1.0);
    return vec3(clip.xy * 0.5 + 0.5, dot(p - nearby_header.origins[nearby_set].xyz, nearby_rects[k].axis.xyz));
}

bool nearby_inside(vec2 uv) {
    return all(greaterThanEqual(uv, vec2(0.0))) && all(lessThanEqual(uv, vec2(1.0)));
}

// TEX_k at uv: rgb radiance, a depth (the far plane outside the texture).
vec4 nearby_texel(uint k, vec2 uv) {
    if (!nearby_inside(uv)) return vec4(0.0, 0.0, 0.0, nearby_rects[k].axis_u.w);
    return textureLod(nearby_tex, vec3(uv, nearby_rects[k].axis_v.w), 0.0);
}

// A texel holds a surface when its depth is in front of the far plane it was cleared to.
bool nearby_covered(uint k, vec4 texel) {
    return texel.a < nearby_rects[k].axis_u.w - 1e-4 * nearby_rects[k].center.w;
}

// The colour of RECT_k along the ray, found by Figs. 16-17 from the rectangle hit t_rect =
// d_far. False where the texel finally looked up is empty (the ray passes beside OBJ_k).
bool nearby_lookup(uint k, vec3 P, vec3 Ray, float t_rect, vec2 uv_rect, out vec3 color, out float dist) {
    GpuNearbyRect r = nearby_rects[k];
    float d_i = r.center.w;
    vec2 uv = uv_rect;
    dist = t_rect;
    if (NEARBY_ITERATIONS > 0u) {
        // Fig. 17: seeds P + alpha_j Ray, alpha_j = d_far (j + 1) / NEARBY_SEEDS. "The
        // highest priority: the z-value of the initial point should be larger than the
        // z-value of the corresponding P_select" (the point lies behind the surface seen
        // from O_R): the first such alpha_j along the ray; otherwise the one whose z is
        // closest to P_select's. P_rect itself is the last seed.
        float best = t_rect, best_err = 1e30;
        bool behind = false;
        for (uint j = 0u; j < NEARBY_SEEDS && !behind; ++j) {
            float alpha = t_rect * float(j + 1u) / float(NEARBY_SEEDS);
            vec3 s = nearby_project(k, P + alpha * Ray);
            vec4 texel = nearby_texel(k, s.xy);
            if (!nearby_covered(k, texel)) continue;
            float err = s.z - texel.a;
            if (err > 0.0) {
                best = alpha;
                behind = true;
            } else if (-err < best_err) {
                best = alpha;
                best_err = -err;
            }
        }
        dist = best;
        // Fig. 16: distance += (depth - z) / cos(theta), theta between Ray and the projection
        // direction. That step assumes the surface perpendicular to the projection direction
        // (exact on the rectangle's own plane); on a surface tilted against it each step
        // shrinks the depth difference only by the factor (slope of the surface's depth along
        // the ray) / cos(theta), so that on sphere_nearby the back wall (34 degrees from its
        // rectangle) was still off after the default 3 steps where rays meet its foot. prism
        // takes Fig. 16's step first and then secant steps through the last two points, the
        // same update with the surface's slope measured instead of assumed (exact for any
        // plane). |cos| is kept >= 0.05 (rays grazing the rectangle: one step then moves at
        // most 20 depth differences instead of dividing by ~0), each step is bounded by the
        // object's size 2 d_i, and the point never goes behind P.
        float cos_t = dot(Ray, r.axis.xyz);
        cos_t = cos_t >= 0.0 ? max(cos_t, 0.05) : min(cos_t, -0.05);
        float tol = NEARBY_TOLERANCE * d_i;
        float prev_dist = 0.0, prev_diff = 0.0;
        bool has_prev = false;
        for (uint i = 0u; i < NEARBY_ITERATIONS; ++i) {
            vec3 s = nearby_project(k, P + dist * Ray);
            vec4 texel = nearby_texel(k, s.xy);
            // A step that left the object's silhouette in TEX_k (an empty texel, whose depth is
            // the far plane's) is halved back towards the last covered point, as Hu & Qin's own
            // d_T search does in prism (glsl/include/hu_qin_exit.glsl): rays meeting the wall
            // a few centimetres above its foot overshot below it and fell back on the floor.
            if (has_prev && !nearby_covered(k, texel)) {
                dist = prev_dist + 0.5 * (dist - prev_dist);
                continue;
            }
            float diff = texel.a - s.z;
            if (abs(diff) <= tol) break;
            float step = diff / cos_t;
            // The secant's slope (diff - prev_diff) / (dist - prev_dist) replaces Fig. 16's
            // -cos(theta) where it has the same sign (the surface is not turned away from the
            // ray's depth faster than the ray itself moves; otherwise Fig. 16's step).
            float slope = has_prev && dist != prev_dist ? (diff - prev_diff) / (dist - prev_dist) : 0.0;
            if (slope * cos_t < 0.0) step = -diff / slope;
            has_prev = nearby_covered(k, texel);
            prev_dist = dist;
            prev_diff = diff;
            dist = max(dist + clamp(step, -2.0 * d_i, 2.0 * d_i), 0.0);
        }
        uv = nearby_project(k, P + dist * Ray).xy;
    }
    vec4 texel = nearby_texel(k, uv);
    color = texel.rgb;
    return nearby_covered(k, texel);
}

// The surface the ray P + t Ray (unit) meets through the selected set's rectangles. Fig. 13
// picks the rectangle whose hit is closest to P and looks up its texture; prism looks up
// every rectangle the ray hits (Figs. 16-17) and keeps the nearest surface found, the
// corrected distance rather than the rectangle's. The two differ where a rectangle lies
// behind its object: RECT_i is perpendicular to O_R O_i, not to the object, so the back
// wall's rectangle (tilted about 34 degrees on sphere_nearby) lies 2 m behind the wall at
// the floor, and rays that meet the bottom of the wall hit the floor's rectangle first and
// showed the floor behind the wall, in the wall's shadow. Without correction
// (NEARBY_ITERATIONS = 0) the corrected distance is the rectangle's, and this is Fig. 13's
// choice, the next rectangle being tried where a texel is empty. False when no rectangle
// holds a surface along the ray.
bool nearby_hit(vec3 P, vec3 Ray, out vec3 color, out float dist) {
    color = vec3(0.0);
    dist = 1e30;
    if (!nearby_has_set()) return false;
    uint first = nearby_header.sets[nearby_set].x;
    uint end = first + min(nearby_header.sets[nearby_set].y, MAX_NEARBY_RECTS);
    bool found = false;
    for (uint k = first; k < end; ++k) {
        float t;
        vec2 uv;
        if (!nearby_rect_hit(k, P, Ray, t, uv)) continue;
        vec3 c;
        float d;
        if (nearby_lookup(k, P, Ray, t, uv, c, d) && d < dist) {
            color = finite_or_zero(c);
            dist = d;
            found = true;
        }
    }
    return found;
}

// Radiance arriving at P from direction Ray (unit): nearby_hit, else the environment map
// ("If there is no rectangle intersected ... index into the environment map").
vec3 nearby_radiance(vec3 P, vec3 Ray) {
    vec3 color;
    float dist;
    return nearby_hit(P, Ray, color, dist) ? color : environment(Ray);
}
#endif
