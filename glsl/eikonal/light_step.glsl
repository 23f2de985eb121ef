// One step of the eikonal light simulator for every patch (Ihrke et al. 2007):
// - section 5.2.1: advance the four corners by the equal-time ray equation, Eqs. 14-15
//   (dx/dt = v / n^2, dv/dt = grad n / n; forward Euler like the paper, the midpoint rule or
//   RK4), so that all particles stay on one wavefront (Appendix, Eqs. 23-24: dS/dt = 1);
// - Eq. 18: the flux dE * A loses exp(-sigma_r dt / n) (ds = dt / n, Eq. 24); without
//   absorption it is constant (the intensity law, Eqs. 16-17);
// - section 5.2.2: voxelize the patch into the irradiance volume. Not the paper's "highest
//   energy ray" with dE = flux / area (Eq. 17) at the midpoint's voxel: near a focus the
//   patch area goes to 0 and that value to infinity (the "catastrophic points" of 5.2.3),
//   and a voxel that a focus narrower than itself crosses kept the focus's peak, not its
//   mean over the voxel: on eikonal_sphere's floor the caustic came out several times too
//   bright. Instead the stream tube's energy is binned by the track-length
//   estimate of the intensity law: a tube of flux Phi = dE A crossing a voxel of volume V
//   over a length l adds Phi l / V to its irradiance, which for a uniform beam filling the
//   voxel (cross-section h^2, l = h) is exactly dE, and which near a focus is the flux
//   through the voxel over its cross-section: finite, and the voxel's mean. The flux is
//   splatted trilinearly (tent of two voxels) at the midpoint of the step's segment, since
//   neighbouring midpoints of patches up to a voxel wide are up to a voxel apart. Every
//   ray's irradiance is summed (Eqs. 6-7 sum over the incoming rays j), and so are the
//   lights, tiles and channels of src/technique/eikonal/eikonal_light.rs, whose runs all add here.
//   With READ_MASK only into the voxels that something looks up (near a surface, or in a
//   scattering volume: src/technique/eikonal/read_mask.rs), since no other voxel is read.
//   With HIGHEST_ENERGY the paper's rule instead (render.eikonal.voxelization =
//   "highest_energy"): the patch's midpoint voxel keeps the ray of the highest dE = flux /
//   area seen there (`voxel_sample`). This kernel raises the voxel's key by an atomic max;
//   which ray won is only known once every patch of the dispatch has, so light_commit.comp,
//   dispatched next, writes the winner's dE and direction. A patch marks the substep it took
//   part in (its mark, `patch_mark`, = substep + 1) for it. The maximum is idempotent, so a take-back is not
//   needed: a split tile's rerun writes the same rays again;
// - section 5.2.3: classify it 0 (eliminate: below the energy threshold, leaving the volume,
//   or its orientation flipped against its direction = it crossed a wavefront singularity,
//   unless KEEP_CROSSED), 1 (retain) or 4 (tessellate: its corners span more than one voxel
//   along an axis);
// - with FRESNEL (render.eikonal.light_fresnel), the Fresnel transmission factor tau of
//   Eq. 5's T(t) on the light's side (`fresnel_loss`).
#include "light_common.glsl"
#include "fresnel.glsl"
layout(local_size_x = LIGHT_GROUP) in;

// Eqs. 14-15 at (x, v); n: the index there.
void rhs(vec3 x, vec3 v, out vec3 dx, out vec3 dv, out float n) {
    vec4 f = sample_field(x);
    n = max(1.0 + f.w, 1e-3);
    dx = v / (n * n);   // Eq. 14
    dv = f.xyz / n;     // Eq. 15
}

// One step of Eqs. 14-15 from (x, v); n0: the index where it began.
void advance(inout vec3 x, inout vec3 v, out float n0) {
    float h = DT, n;
    if (INTEGRATOR == EIKONAL_RK4) {
        vec3 k1x, k1v, k2x, k2v, k3x, k3v, k4x, k4v;
        rhs(x, v, k1x, k1v, n0);
        rhs(x + 0.5 * h * k1x, v + 0.5 * h * k1v, k2x, k2v, n);
        rhs(x + 0.5 * h * k2x, v + 0.5 * h * k2v, k3x, k3v, n);
        rhs(x + h * k3x, v + h * k3v, k4x, k4v, n);
        x += h / 6.0 * (k1x + 2.0 * k2x + 2.0 * k3x + k4x);
        v += h / 6.0 * (k1v + 2.0 * k2v + 2.0 * k3v + k4v);
    } else if (INTEGRATOR == EIKONAL_MIDPOINT) {
        // Second order with two field samples: the slope at the half step's Euler estimate.
        vec3 k1x, k1v, k2x, k2v;
        rhs(x, v, k1x, k1v, n0);
        rhs(x + 0.5 * h * k1x, v + 0.5 * h * k1v, k2x, k2v, n);
        x += h * k2x;
        v += h * k2v;
    } else {
        vec3 dx, dv;
        rhs(x, v, dx, dv, n0);
        x += h * dx;
        v += h * dv;
    }
}

// `advance` where the field is uniform, index n: every stage sees grad n = 0 and the same n,
// so v stays and x moves by DT v / n^2, computed with the integrator's own arithmetic so
// that the result is the same to the bit.
void straight_step(inout vec3 x, vec3 v, float n) {
    vec3 k = v / (n * n);
    if (INTEGRATOR == EIKONAL_RK4) {
        x += DT / 6.0 * (k + 2.0 * k + 2.0 * k + k);
    } else {
        x += DT * k;
    }
}

// Where the line o + t d enters and leaves the box lo..hi (slab test): near > far where it
// misses.
void box_span(vec3 o, vec3 d, vec3 lo, vec3 hi, out float near, out float far) {
    vec3 inv = 1.0 / mix(vec3(1e-30), d, greaterThan(abs(d), vec3(1e-30)));
    vec3 t0 = (lo - o) * inv, t1 = (hi - o) * inv;
    vec3 tl = min(t0, t1), th = max(t0, t1);
    near = max(max(tl.x, tl.y), tl.z);
    far = min(min(th.x, th.y), th.z);
}

// How far a particle at x moving along unit d may go in a straight line: through uniform
// bricks inside the field's box (bricks.glsl), and outside it up to the box widened by a
// voxel (within which the trilinear lookup still reads the boundary voxels); unbounded on a
// line that never meets that box.
float straight_reach(vec3 x, vec3 d) {
    ivec3 size = textureSize(field, 0);
    size.z /= int(CHANNELS);
    vec3 voxel = (VOL_MAX - VOL_MIN) / vec3(size);
    vec3 lo = VOL_MIN - voxel, hi = VOL_MAX + voxel;
    if (all(greaterThanEqual(x, lo)) && all(lessThanEqual(x, hi))) return uniform_leap(x, d, VOL_MIN, VOL_MAX, size);
    float near, far;
    box_span(x, d, lo, hi, near, far);
    return near <= far && far > 0.0 ? max(near, 0.0) : 1e30;
}

// Does the straight ray (outside the medium n = 1) from o along d still reach the box?
bool heads_into_box(vec3 o, vec3 d) {
    float near, far;
    box_span(o, d, LIGHT_MIN, LIGHT_MAX, near, far);
    return near <= far && far > 0.0;
}

// The boundary band at x (nearest voxel): where the smoothed index crosses a jump.
bool in_band(vec3 x) {
    ivec3 size = textureSize(band_map, 0);
    vec3 u = (x - VOL_MIN) / (VOL_MAX - VOL_MIN) * vec3(size);
    if (any(lessThan(u, vec3(0.0))) || any(greaterThanEqual(u, vec3(size)))) return false;
    return texelFetch(band_map, ivec3(u), 0).a > 0.5;
}

float band_reflectance(vec3 x) {
    ivec3 size = textureSize(reflectance_map, 0);
    ivec3 q = clamp(ivec3((x - VOL_MIN) / (VOL_MAX - VOL_MIN) * vec3(size)), ivec3(0), size - 1);
    return texelFetch(reflectance_map, q, 0).a;
}

// The flux a patch keeps at the end of a run inside a band: the run began with the mean
// optical direction va (|va| = n_a) and ends with vb. Across the run n dx/ds keeps its
// component along the boundary (Snell), so vb - va is along the boundary's normal; if the
// patch crossed (it moves the same way along the normal at both ends) it keeps
// 1 - rho F(theta_a, n_a / n_b); if the ray equation turned it back (total internal
// reflection) nothing is lost.
float fresnel_transmission(vec3 va, vec3 vb, float rho) {
    vec3 N = vb - va;
    if (dot(N, N) < 1e-12) return 1.0;
    N = normalize(N);
    if (!(dot(va, N) * dot(vb, N) > 0.0)) return 1.0;
    float na = length(va), nb = length(vb);
    float F = rho * fresnel_dielectric(abs(dot(va, N)) / na, na / max(nb, 1e-3));
    return 1.0 - clamp(F, 0.0, 1.0);
}

// The Fresnel loss of one step from mid0 (mean optical direction v0) to mid (v1), as the view
// renderer's march splits a band into monotone runs of the index (glsl/eikonal/view.frag:
// a thin wall, or two faces whose bands merge, is two runs, up then down). The run in
// progress is the optical direction where it began, in v[1..3].w (0: none); its direction of
// change is the sign of n(mid0) - n_a. A run ends where the band does (at mid) or where the
// index turns (at mid0, where the next run begins), unless the index has changed by less
// than MIN_JUMP over it: on the plateau inside a region the field's rounding wobbles, and the
// normal vb - va of such a run is noise, which at a grazing angle would give F near 1.
const float MIN_JUMP = 1e-3;
void fresnel_loss(inout Patch p, vec3 mid0, vec3 v0, vec3 mid, vec3 v1) {
    vec3 va = vec3(p.v[1].w, p.v[2].w, p.v[3].w);
    bool band = in_band(mid);
    if (dot(va, va) == 0.0) {
        if (band) va = v0;
    } else {
        float n0 = length(v0), n1 = length(v1), na = length(va);
        bool turned = (n0 - na) * (n1 - n0) < 0.0;
        vec3 vb = turned ? v0 : v1;
        if (!band || (turned && abs(length(vb) - na) >= MIN_JUMP)) {
            if (abs(length(vb) - na) >= MIN_JUMP) set_patch_flux(p, patch_flux(p) * fresnel_transmission(va, vb, band_reflectance(mid0)));
            va = band ? v0 : vec3(0.0);
        }
    }
    p.v[1].w = va.x;
    p.v[2].w = va.y;
    p.v[3].w = va.z;
}

// Track-length deposit at `at` of `flux_len`, flux (W) times track length (m), of a segment
// centred there (section 5.2.2, see the top).
void deposit(vec3 at, vec3 flux_len, vec3 dir) {
    ivec3 size = imageSize(irradiance);
    vec3 voxel = (LIGHT_MAX - LIGHT_MIN) / vec3(size);
    // Up to a voxel outside the box the splat still reaches the boundary voxels (without
    // it they would miss half their deposits).
    if (!(max(flux_len.r, max(flux_len.g, flux_len.b)) > 0.0) || any(lessThan(at, LIGHT_MIN - voxel))
        || any(greaterThan(at, LIGHT_MAX + voxel))) return;
    vec3 u = (at - LIGHT_MIN) / voxel - 0.5;
    // The eight voxels it adds to are within one of the voxel that holds its centre (clamped
    // into the volume: those outside are not added to).
    if (!marked_read(clamp(ivec3(floor(u + 0.5)), ivec3(0), size - 1), size)) return;
    vec3 e = run.sign * flux_len / (voxel.x * voxel.y * voxel.z);
    if (any(isnan(e)) || any(isinf(e))) return;
    vec3 d = dir * (e.r + e.g + e.b);
    ivec3 i0 = ivec3(floor(u));
    vec3 f = u - vec3(i0);
    for (int c = 0; c < 8; ++c) {
        ivec3 o = ivec3(c & 1, (c >> 1) & 1, (c >> 2) & 1);
        ivec3 q = i0 + o;
        if (any(lessThan(q, ivec3(0))) || any(greaterThanEqual(q, size))) continue;
        vec3 w3 = mix(1.0 - f, f, vec3(o));
        float w = w3.x * w3.y * w3.z;
        if (!(w > 0.0)) continue;
        // Zero channels (one channel's run of a dispersive volume) cost no atomics, nor do
        // a grey light's equal ones.
        if (e.r != 0.0) accum_add(q, 0, w * e.r);
        if (GRAY == 0u && e.g != 0.0) accum_add(q, 1, w * e.g);
        if (GRAY == 0u && e.b != 0.0) accum_add(q, 2, w * e.b);
        if (DIRECTION_NEAREST == 0u) {
            accum_add(q, 3, w * d.x);
            accum_add(q, 4, w * d.y);
            accum_add(q, 5, w * d.z);
        }
    }
    if (DIRECTION_NEAREST != 0u) {
        ivec3 q = ivec3(floor(u + 0.5));
        if (all(greaterThanEqual(q, ivec3(0))) && all(lessThan(q, size))) {
            accum_add(q, 3, d.x);
            accum_add(q, 4, d.y);
            accum_add(q, 5, d.z);
            accum_add(q, 6, e.r + e.g + e.b);
        }
    }
}

// `light_substeps` dispatches of this kernel advance the same list before it is compacted
// (the HistoPyramid and the output generator, section 5.2.3): at each after the first
// (run.substep > 0) a patch steps on only while it is retained, so every patch takes the
// steps, deposits and classes of one compaction per step; only the order of the float
// additions changes. Patches of one list are then at different times, so each carries its
// own step count (`patch_steps`) and is eliminated at the run's step budget. (A loop over the
// substeps inside one invocation cost lavapipe half again the step's time.)
//
// Straight steps (LEAP_STEPS > 0, render.eikonal.light_leaps): where the integrated step began
// with every corner inside a uniform region (no gradient for any lookup to read: bricks.glsl,
// or beyond the field's box), Eqs. 14-15 keep v and move x by DT v / n^2 per step, n the
// index the step began at; a patch then takes up to LEAP_STEPS more steps in the same
// dispatch, as many as keep each corner inside its region, each classified and deposited
// exactly as a step of its own, stopping at the first that is not retained. The wavefront
// is the same to the bit (`straight_step`), in fewer dispatches: a patch crossing the uniform
// inside of a glass ball or the air below it is in the list a fraction of the times. The
// loop holds the classification and the one deposit call: a CPU device runs every call
// site's atomics.
void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= state.count) return;
    if (run.substep > 0u && classes[i] != 1u) return;
    Patch p = src_patch(i);
    uint steps = patch_steps(p);
    if (steps >= run.max_steps) {
        classes[i] = 0u;
        return;
    }
    vec3 mid0 = patch_mid(p);
    vec3 flux0 = patch_flux(p);
    vec3 v0 = 0.25 * (p.v[0].xyz + p.v[1].xyz + p.v[2].xyz + p.v[3].xyz);
    // Straight steps each corner's region allows after this one (see above).
    float leaps = float(LEAP_STEPS);
    float n_start[4];
    for (int c = 0; c < 4; ++c) {
        vec3 x = p.x[c].xyz, v = p.v[c].xyz;
        float n0;
        advance(x, v, n0);
        if (LEAP_STEPS > 0u) {
            float per_step = DT * length(p.v[c].xyz) / (n0 * n0);
            n_start[c] = n0;
            leaps = min(leaps, floor(straight_reach(p.x[c].xyz, normalize(p.v[c].xyz)) / per_step) - 1.0);
        }
        p.x[c].xyz = x;
        p.v[c].xyz = v;
    }
    leaps = min(leaps, float(run.max_steps - steps - 1u));
    vec3 mid = patch_mid(p);
    if (FRESNEL != 0u) {
        // The mean direction of travel with the field's index at the midpoint as its length
        // (the integrator keeps |v| = n only to its order).
        vec3 v1 = p.v[0].xyz + p.v[1].xyz + p.v[2].xyz + p.v[3].xyz;
        fresnel_loss(p, mid0, normalize(v0) * index_at(mid0), mid, normalize(v1) * index_at(mid));
    }
    // Eq. 18 with the extinction volume (sigma_r = sigma_a + sigma_s, Eq. 5); none in a
    // uniform region, so only for the integrated step.
    vec3 sigma = extinction_at(mid);
    if (any(greaterThan(sigma, vec3(0.0)))) {
        set_patch_flux(p, patch_flux(p) * exp(-sigma * DT / index_at(mid)));
    }
    vec3 voxel = (LIGHT_MAX - LIGHT_MIN) / vec3(imageSize(irradiance));
    uint cls = 1u, taken = 0u;
    for (uint s = 0u;; ++s) {
        if (s > 0u) {
            for (int c = 0; c < 4; ++c) {
                vec3 x = p.x[c].xyz;
                straight_step(x, p.v[c].xyz, n_start[c]);
                p.x[c].xyz = x;
            }
            mid0 = mid;
            flux0 = patch_flux(p);
            mid = patch_mid(p);
        }
        vec3 normal = patch_normal(p);
        vec3 dir = patch_dir(p);
        bool finite_patch = !any(isnan(normal)) && !any(isinf(normal)) && dot(dir, dir) > 0.0;
        bool singular = !finite_patch || (KEEP_CROSSED == 0u && !(dot(normal, dir) > 0.0));
        vec3 lo = min(min(p.x[0].xyz, p.x[1].xyz), min(p.x[2].xyz, p.x[3].xyz));
        vec3 hi = max(max(p.x[0].xyz, p.x[1].xyz), max(p.x[2].xyz, p.x[3].xyz));
        // Within its own size of the box a patch is split already: each step halves it while
        // moving half a voxel, so it is down to a voxel when it enters (a patch of many voxels
        // deposited at its midpoint would leave holes in the first layers).
        vec3 margin = max(voxel, vec3(max(hi.x - lo.x, max(hi.y - lo.y, hi.z - lo.z))));
        bool near_box = all(greaterThanEqual(hi, LIGHT_MIN - margin)) && all(lessThanEqual(lo, LIGHT_MAX + margin));
        cls = 1u;
        vec3 flux = patch_flux(p);
        if (singular || max(flux.r, max(flux.g, flux.b)) < run.min_flux) {
            cls = 0u;
        } else if (!near_box && !heads_into_box(mid, dir)) {
            cls = 0u;   // left the simulation volume (and will not re-enter: straight in air)
        } else if (near_box && any(greaterThan(hi - lo, voxel))) {
            cls = 4u;   // tessellate; outside the box rays are straight and need no resolution
        }
        uint step_now = steps + s;
        taken = s + 1u;
        if (HIGHEST_ENERGY != 0u) {
            uint mark = 0u;
#ifndef ACCUM_FLOAT_ATOMICS
            ivec3 q;
            vec3 dE;
            uint key;
            if (!singular && voxel_sample(p, q, dE, key)) {
                imageAtomicMax(accum, accum_texel(q, 6), key);
                mark = run.substep + 1u;
            }
#endif
            set_patch_steps(p, step_now + 1u, mark);
        } else {
            // With DEPOSIT_EVERY = 2 a retained patch adds every other step's chord together
            // with the next one's: one splat per voxel of travel instead of two at the default
            // half-voxel step (the trilinear tent, two voxels wide, still sums to a constant
            // along a straight track), and half the atomics. The chord it waited on is taken as
            // long as this one (exact for straight travel at constant speed) and carried the
            // flux it had at the end of it.
            vec3 chord = mid - mid0;
            float len = length(chord);
            bool deferred = patch_mark(p) != 0u;
            bool defer = DEPOSIT_EVERY == 2u && !deferred && cls == 1u && step_now + 1u < run.max_steps;
            set_patch_steps(p, step_now + 1u, defer ? 1u : 0u);
            // One call: a CPU device runs every call site's atomics, masked or not.
            vec3 at = mid0 + 0.5 * chord;
            vec3 flux_len = flux * len;
            if (deferred) {
                // Both chords, centred where they meet; a singular patch only the one before.
                at = singular ? mid0 - 0.5 * chord : mid0;
                flux_len = singular ? flux0 * len : (flux0 + flux) * len;
            }
            if (deferred ? finite_patch : !singular && !defer) deposit(at, flux_len, normalize(dir));
        }
        if (!(cls == 1u && float(s) < leaps)) break;
    }
    src[i] = p;
    classes[i] = cls;
    atomicAdd(state.advanced, taken);
}
