// Distance impostors, Szirmay-Kalos, Aszodi, Lazanyi, Premecz 2005, "Approximate Ray-Tracing
// on the GPU with Distance Impostors" (Eurographics 2005), §2 and §3: Hit(), the ray-hit
// approximation from the distances stored in a cube map around a reference point o.
//
// Every vector here is relative to o (the paper's Fig. 2 puts o at the origin). A map stores
// the distance |v'| of the surface visible from o in direction v in one channel: `channel` 3
// (alpha of a radiance or normal map) or 0 (a separate R32F distance cube, §6: "the speed
// improves by an additional 20 percent if the distance values are separated").
#ifndef PRISM_IMPOSTOR_GLSL
#define PRISM_IMPOSTOR_GLSL

// IMPOSTOR_NO_SURFACE (the cleared distance where no surface is seen from o) and
// IMPOSTOR_MISS (a looked-up distance above it is "no surface") come from
// src/shader_shared.rs, shared with the passes that clear the maps.

// |v'|: distance of the surface visible from o in direction v (any length, not 0).
float impostor_distance(samplerCube map, uint channel, vec3 v) {
    vec4 t = textureLod(map, v, 0.0);
    return channel == 0u ? t.r : t.a;
}

// |l| / |l'| for a point l on the ray (§2.2): < 1 undershooting (in front of the surface),
// > 1 overshooting (behind it), 1 on it. The reference point itself is in front of every
// surface; a zero stored distance (o on a surface) counts as overshooting.
float impostor_ratio(samplerCube map, uint channel, vec3 l) {
    float len = length(l);
    if (len <= 0.0) return 0.0;
    float stored = impostor_distance(map, channel, l);
    return stored > 0.0 ? len / stored : 2.0;
}

// One step of Eq. 6: the root of the line through (d_a, ratio_a) and (d_b, ratio_b) of
// f(d) = ratio - 1. Returns the step from d_a; 0 where the two ratios agree (a flat f gives
// no direction; the caller keeps d_a).
float impostor_step(float d_a, float ratio_a, float d_b, float ratio_b) {
    float denom = ratio_a - ratio_b;
    if (abs(denom) < 1e-12) return 0.0;
    return (d_a - d_b) * (1.0 - ratio_a) / denom;
}

// Hit(x, R) of §3: the ray parameter d of the approximate hit of the ray x + R d (x relative
// to o, R unit) with the surface stored in `map`, after `iterations` refinement steps.
//   d_p: perpendicular-surface guess (§2.1, from Eq. 2 and R.p = |r|): d_p = |r| - R.x.
//   d_l: planar guess between r and p' (Eq. 4): d_l = d_p + |r| (1 - |p|/|p'|).
//   Refinement (§2.2): Eq. 6 with the latest point paired with the latest approximation of
//   the opposite type (false position). Until an overshooting point exists, the point at
//   infinity (ray parameter infinite, direction R, "a sure overshooting") plays its role:
//   Eq. 6 with d_b -> infinity gives the step |r| (1 - ratio). Until an undershooting point
//   exists, default point r substitutes it the same way ("the last option is safe").
// Ray parameters are kept non-negative ("to avoid ray flipping").
// `iterations` = 0 returns d_l: the initial guesses only.
float impostor_hit_distance(samplerCube map, uint channel, vec3 x, vec3 R, uint iterations) {
    float r1 = impostor_distance(map, channel, R);                // |r|
    float dp = max(r1 - dot(x, R), 0.0);                           // §2.1
    float ppp = impostor_ratio(map, channel, x + R * dp);         // |p| / |p'|
    bool have_under = false, have_over = false;
    float d_under = 0.0, r_under = 0.0, d_over = 0.0, r_over = 0.0;
    if (ppp < 1.0) {
        have_under = true; d_under = dp; r_under = ppp;
    } else {
        have_over = true; d_over = dp; r_over = ppp;
    }
    float dl = max(dp + r1 * (1.0 - ppp), 0.0);                    // Eq. 4
    for (uint i = 0u; i < iterations; ++i) {
        float llp = impostor_ratio(map, channel, x + R * dl);     // |l| / |l'|
        float ddl;
        if (llp < 1.0) {                                           // undershooting
            ddl = have_over ? impostor_step(dl, llp, d_over, r_over) : r1 * (1.0 - llp);
            have_under = true; d_under = dl; r_under = llp;
        } else {                                                   // overshooting
            ddl = have_under ? impostor_step(dl, llp, d_under, r_under) : r1 * (1.0 - llp);
            have_over = true; d_over = dl; r_over = llp;
        }
        dl = max(dl + ddl, 0.0);                                   // Eq. 6, no flip
    }
    return dl;
}

// The approximate hit point l = x + R d (relative to o).
vec3 impostor_hit(samplerCube map, uint channel, vec3 x, vec3 R, uint iterations) {
    return x + R * impostor_hit_distance(map, channel, x, R, iterations);
}

// Whether direction v of the map sees no surface (the ray leaves the impostor).
bool impostor_missed(samplerCube map, uint channel, vec3 v) {
    return !(impostor_distance(map, channel, v) < IMPOSTOR_MISS);
}
#endif
