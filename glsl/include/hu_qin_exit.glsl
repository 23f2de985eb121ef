// Hu & Qin 2007 §2.1.2-2.1.3: where the refracted ray T1 leaves the refractor, found in a
// view's front and back depth/normal layers. Shared by the camera view
// (glsl/refraction/hu_qin.frag, perspective) and the impostor textures' parallel projections
// (glsl/nearby/impostor_body.glsl, §2.2.1: "we render TEX_k using the above method").
// The including shader defines, before including this file:
//   constants SEARCH_STEPS (Fig. 7's halvings) and MAX_ITERATIONS (Fig. 9's steps);
//   bool exit_covered(bool front, vec2 uv): the front (true) or back (false) layer holds a
//     surface at uv (the back layer's coverage is the refractor's silhouette);
//   bool exit_layer(bool front, vec2 uv, out float depth): exit_covered, and where covered
//     that layer's depth at uv, a distance that grows away from the eye along the view
//     direction, from the one texel both read;
//   vec4 exit_affine(vec3 P, float w): the view's map of the homogeneous point (P, w) before
//     its divide, (x, y, depth, divisor), depth in the layers' measure: affine in (P, w), so
//     along a ray P1 + t T1 it is exit_affine(P1, 1) + t exit_affine(T1, 0), and the depth of
//     a direction (w = 0) is the rate at which depth grows along it;
//   vec2 exit_affine_uv(vec4 a): the uv of such a point, exit_project's;
//   constant D_T_STEP: D_T_STEP_PAPER or D_T_STEP_NEWTON (hu_qin_search_d_t);
//   constant D_T_BRACKET: 1 keeps the sign change of the search's residual (hu_qin_search_d_t);
//   vec2 exit_project(vec3 P): P's uv in the view;
//   vec3 exit_back_point(vec2 uv): the back layer's surface point at uv.
#ifndef PRISM_HU_QIN_EXIT_GLSL
#define PRISM_HU_QIN_EXIT_GLSL

// Fig. 7: binary search from p1 along the unit uv direction t1 for the dividing pixel p_e,
// the last pixel inside the silhouette. The interval [inside, outside] starts at [0, span]
// in uv units and each step halves it.
vec2 hu_qin_dividing_pixel(vec2 p1, vec2 t1, float span) {
    float inside = 0.0, outside = span;
    for (uint i = 0; i < SEARCH_STEPS; ++i) {
        float mid = 0.5 * (inside + outside);
        if (exit_covered(false, p1 + mid * t1)) inside = mid; else outside = mid;
    }
    return p1 + inside * t1;
}

// §2.1.2, Fig. 5: whether T1 leaves through a front-facing surface. t1 is T1 projected into
// the view (P1 and the point `probe` along T1); p_e the dividing pixel along it (Fig. 7) and
// P_e its back-layer point; theta_1 between V and T1, theta_2 between V and P1 -> P_e, both in
// the plane of the eye, P1 and P2: T1 turned further from V than the chord to the dividing
// point leaves through the front-facing surface. Back-facing where t1 has no length (T1
// along V).
bool hu_qin_exit_is_front(vec3 V, vec2 p1, vec3 P1, vec3 T1, float probe, float span) {
    vec2 t1 = exit_project(P1 + probe * T1) - p1;
    if (!(dot(t1, t1) > 1e-14)) return false;
    vec2 pe = hu_qin_dividing_pixel(p1, normalize(t1), span);
    vec3 Pe = exit_back_point(pe);
    vec3 chord = Pe - P1;
    // theta_1 > theta_2 compared as cosines (acos decreases): cos theta_2 = -1 (theta_2 = pi)
    // where the chord has no length, which no theta_1 exceeds.
    float cos_1 = clamp(dot(V, T1), -1.0, 1.0);
    float cos_2 = dot(chord, chord) > 0.0 ? clamp(dot(V, normalize(chord)), -1.0, 1.0) : -1.0;
    return cos_1 < cos_2;
}

// §2.1.3, Fig. 9: d_T by the iterative lookup, against the front (flag -1) or back (flag 1)
// layer: each step is the depth difference between the layer and the current point
// (D_T_STEP_PAPER). That difference is measured along the view axis while the step is taken
// along T1, so for a T1 oblique to the axis it under- or overshoots and the iteration
// converges linearly. D_T_STEP_NEWTON divides it by the rate |T1 . axis| at which depth
// changes along T1 (at least 0.1, so at most 10 times the paper's step): a Newton step for a
// layer perpendicular to the axis. Against the converged image of sphere_env at 128^2 (1024
// iterations), pixels off by more than 2/255 after 3 and 4 iterations: 416 and 112 with the
// paper's step, 326 and 48 with Newton's; none and none after 8. (The secant method on the
// same difference did worse, 116 after 6: the nearest-texel layer depth is a step function.)
// Returns false if P2 left the layer's coverage (section 4: then the exit is front-facing);
// the step is then halved and the search continues from the last point inside. `found`: some
// step landed on a covered point (d_T > 0 was accepted).
// D_T_BRACKET (render.hu_qin.d_t_bracket, prism's departure): the search keeps the interval
// [lo, hi] of d_T in which its residual, the step, changes sign (lo: the layer lies further
// along T1; hi: P2 is past it, or outside the layer's coverage), and halves it where the
// step would leave it. Fig. 9 stops only on a step below the tolerance, which never comes
// where the layer has no root along T1: the nearest-texel depth is a step function, and where
// one texel's depth is above P2's and the next's below by more than the tolerance (a grazing
// exit), or the layer jumps (where a fold of the mesh hides the exit surface from the eye),
// the iteration oscillates across the jump until MAX_ITERATIONS (on bunny_env at 512^2, 2 429
// of its 83 914 pixels, nearly every step reversing). The interval closes on the jump
// instead, and the search stops when it is below the tolerance: the exit where the layer
// changes side of T1, found in about log2(thickness / tolerance) halvings. Where Fig. 9
// converges inside the interval, its steps are taken unchanged.
bool hu_qin_search_d_t(bool front, vec3 P1, vec3 T1, float tol, float step0, out float d_T, out bool found) {
    float flag = front ? -1.0 : 1.0;
    float step = step0;
    bool stayed = true;
    found = false;
    d_T = 0.0;
    // d_T >= 0 (P1 is on the front layer, in front of the back one); no upper bound yet.
    float lo = 0.0, hi = 3.4e38;
    // P2 = P1 + d_T T1 projected as one multiply-add per component from the two ends' maps,
    // not a matrix product per step.
    vec4 a1 = exit_affine(P1, 1.0), aT = exit_affine(T1, 0.0);
    for (uint i = 0; i < MAX_ITERATIONS; ++i) {
        float next = max(d_T + step, 0.0);
        if (D_T_BRACKET != 0u && hi < 3.4e38 && !(next > lo && next < hi)) next = 0.5 * (lo + hi);
        vec4 a2 = a1 + next * aT;
        float z;
        if (!exit_layer(front, exit_affine_uv(a2), z)) {
            stayed = false;
            step *= 0.5;
            hi = min(hi, next);
            continue;
        }
        d_T = next;
        found = true;
        step = flag * (z - a2.z);
        if (abs(step) < tol) break;
        if (step > 0.0) lo = max(lo, d_T); else hi = min(hi, d_T);
        if (D_T_BRACKET != 0u && hi - lo < tol) break;
        if (D_T_STEP == D_T_STEP_NEWTON) step /= max(abs(aT.z), 0.1);
    }
    return stayed;
}
#endif
