#version 450
// Eikonal view renderer (Ihrke et al. 2007, sections 4.1 and 5.3): the camera ray enters
// the volume's proxy box (ray-box intersection; section 5.1's "suitable proxy geometry to
// start the ray casting"), is marched through the smoothed index field with the ray
// equation dx/ds = v/n, dv/ds = grad n (Eqs. 9-10; Euler Eqs. 11-12, the midpoint rule,
// classical RK4, or velocity Verlet of the same equation as x'' = n grad n), and its exit
// direction looks up the environment (the background radiance L_bg of Eq. 1).
// No explicit ray-surface intersection: the bending comes from grad n alone.
// Along the path (the material volumes of src/scene/volume_sources.rs):
// RGB extinction (Eq. 5), emission (L_e of Eq. 2, integrated with Eq. 1), Fresnel reflection
// at the boundary indicator (delta rho L_r of Eq. 2, the reflected ray looks up the
// environment: section 5.3's "first reflection"; T of Eq. 5 takes the transmitted part),
// and dispersion: one march per RGB channel through its own index field (section 5.3).
// Exit and reflected rays meet the nearby scene geometry (exact
// triangles of flat receivers, Hu & Qin impostors; §6, Fig. 7) before the environment.
#include "frame.glsl"
#include "environment.glsl"
#include "fresnel.glsl"
layout(constant_id = 0) const uint INTEGRATOR = EIKONAL_EULER;
layout(constant_id = 1) const float STEP = 0.01;      // metres of arc length per step
layout(constant_id = 2) const uint MAX_STEPS = 1024u;
layout(constant_id = 3) const float BOX_MIN_X = -1.0;
layout(constant_id = 4) const float BOX_MIN_Y = -1.0;
layout(constant_id = 5) const float BOX_MIN_Z = -1.0;
layout(constant_id = 6) const float BOX_MAX_X = 1.0;
layout(constant_id = 7) const float BOX_MAX_Y = 1.0;
layout(constant_id = 8) const float BOX_MAX_Z = 1.0;
// ---- channels and materials ----
layout(constant_id = 9) const uint CHANNELS = 1u;    // index slabs: 3 = per-channel index
layout(constant_id = 10) const uint MATERIALS = 0u;  // 0: the material volumes are stand-ins
// ---- end of the material volumes ----
// ---- single scattering from the light simulator (scatter.glsl) ----
layout(constant_id = 11) const uint SCATTER = 0u;           // 1: a light simulation ran
layout(constant_id = 12) const float LIGHT_MIN_X = 0.0;    // the irradiance volume's box
layout(constant_id = 13) const float LIGHT_MIN_Y = 0.0;
layout(constant_id = 14) const float LIGHT_MIN_Z = 0.0;
layout(constant_id = 15) const float LIGHT_MAX_X = 1.0;
layout(constant_id = 16) const float LIGHT_MAX_Y = 1.0;
layout(constant_id = 17) const float LIGHT_MAX_Z = 1.0;
#include "scatter.glsl"
// ---- end of single scattering ----
// ---- nearby geometry for exit and reflected rays (nearby_exit.glsl) ----
layout(constant_id = 18) const uint TRIANGLES_IN_BOX = 0u;  // 1: test every step against the triangles
layout(constant_id = 19) const uint NEARBY_ITERATIONS = 3u; // Fig. 16 correction iterations
layout(constant_id = 20) const float NEARBY_TOLERANCE = 1e-3;
layout(constant_id = 21) const uint NEARBY_SEEDS = 8u;
// Ihrke et al.'s exit rays keep Hu & Qin's Fig. 13 rectangle choice (glsl/include/nearby.glsl).
const uint NEARBY_LOOKUP = NEARBY_LOOKUP_PAPER;
#include "lighting.glsl"
#include "receiver.glsl"
// 0: the scene keeps no nearby object for impostor rectangles, and the exit rays' lookup of
// them (nearby_exit.glsl) is compiled out.
layout(constant_id = 28) const uint IMPOSTORS = 1u;
#include "nearby_exit.glsl"
// ---- end of the nearby geometry ----
// Which material volumes hold anything: one that is all zero is never sampled.
layout(constant_id = 22) const uint EXTINCTION = 1u;
layout(constant_id = 23) const uint EMISSION = 1u;
// Merged steps where the field is weak or constant (render.eikonal.leaps, weak_gradient).
layout(constant_id = 24) const uint LEAPS = 0u;
layout(constant_id = 26) const uint HARDWARE_FILTER = 0u;  // the device's trilinear field lookup
// A ray whose transmittance falls below this in every channel it carries stops there
// (render.eikonal.min_transmittance; 0: never).
layout(constant_id = 27) const float MIN_TRANSMITTANCE = 0.0;
layout(set = 1, binding = BINDING_GBUF_DEPTH) uniform sampler2D gbuf_depth;
// xyz: grad n per metre, w: n - 1, at the voxel centres; CHANNELS slabs stacked along z.
layout(set = 1, binding = BINDING_EIKONAL_FIELD) uniform sampler3D field;
// ---- material volumes ----
layout(set = 1, binding = BINDING_EIKONAL_EXTINCTION) uniform sampler3D extinction_map;  // sigma_a + sigma_s, g
layout(set = 1, binding = BINDING_EIKONAL_ALBEDO) uniform sampler3D albedo_map;          // albedo (rgb)
layout(set = 1, binding = BINDING_EIKONAL_EMISSION) uniform sampler3D emission_map;      // emission (rgb)
// The march map, x fastest (src/technique/eikonal/volume.rs, `march_map`): per voxel the
// boundary band's reflectance factor (f32 bits, -1 outside the band) whose eight lowest
// mantissa bits hold the Chebyshev distance in voxels to the nearest voxel where the field is
// not weak, or not constant with no threshold (`weak_reach`).
layout(set = 1, binding = BINDING_EIKONAL_MARCH) uniform usamplerBuffer march_texels;
// ---- end of the material volumes ----
layout(location = 0) in vec2 in_uv;
layout(location = 0) out vec4 out_radiance;

const vec3 BOX_MIN = vec3(BOX_MIN_X, BOX_MIN_Y, BOX_MIN_Z);
const vec3 BOX_MAX = vec3(BOX_MAX_X, BOX_MAX_Y, BOX_MAX_Z);

// The size of one index slab (the field holds CHANNELS of them along z).
ivec3 slab_size() {
    ivec3 s = textureSize(field, 0);
    return ivec3(s.xy, s.z / int(CHANNELS));
}

// One voxel of slab `c`; beyond the box the air has n = 1 and no gradient.
vec4 voxel(ivec3 q, ivec3 size, int c) {
    bool inside = all(greaterThanEqual(q, ivec3(0))) && all(lessThan(q, size));
    return inside ? texelFetch(field, q + ivec3(0, 0, c * size.z), 0) : vec4(0.0);
}

// Trilinear interpolation in full precision (the same on every device), (grad n, n - 1);
// with HARDWARE_FILTER the device's filtering (render.eikonal.hardware_filtering: one slab,
// a linear sampler whose border is zero, as `voxel` beyond the box).
vec4 sample_field(vec3 x, int c) {
    if (HARDWARE_FILTER != 0u) return textureLod(field, (x - BOX_MIN) / (BOX_MAX - BOX_MIN), 0.0);
    ivec3 size = slab_size();
    vec3 u = (x - BOX_MIN) / (BOX_MAX - BOX_MIN) * vec3(size) - 0.5;
    u = clamp(u, vec3(-1.0), vec3(size));
    vec3 f = fract(u);
    ivec3 i = ivec3(floor(u));
    vec4 c00 = mix(voxel(i, size, c), voxel(i + ivec3(1, 0, 0), size, c), f.x);
    vec4 c10 = mix(voxel(i + ivec3(0, 1, 0), size, c), voxel(i + ivec3(1, 1, 0), size, c), f.x);
    vec4 c01 = mix(voxel(i + ivec3(0, 0, 1), size, c), voxel(i + ivec3(1, 0, 1), size, c), f.x);
    vec4 c11 = mix(voxel(i + ivec3(0, 1, 1), size, c), voxel(i + ivec3(1, 1, 1), size, c), f.x);
    return mix(mix(c00, c10, f.y), mix(c01, c11, f.y), f.z);
}

// The right-hand side of Eqs. 9-10 for the field sample s = (grad n, n - 1) at x:
// (dx/ds, dv/ds) = (v / n, grad n).
void rhs_at(vec4 s, vec3 v, out vec3 dx, out vec3 dv) {
    dx = v / max(1.0 + s.w, 1e-3);
    dv = s.xyz;
}

void rhs(vec3 x, vec3 v, int c, out vec3 dx, out vec3 dv) {
    rhs_at(sample_field(x, c), v, dx, dv);
}

#include "cube.glsl"

// The march texel beyond the box, the air's: -1's bits, reach 0.
const uint MARCH_OUTSIDE = 0xbf800000u;
// The voxel holding x (inside the box).
ivec3 march_cell(vec3 x) {
    return ivec3((x - BOX_MIN) / (BOX_MAX - BOX_MIN) * vec3(slab_size()));
}
// The march map at the voxel holding x: one fetch per step, from a buffer of 32-bit texels:
// on lavapipe a fetch from an RGBA16F volume was a tenth of the march, a storage-buffer load
// (a loop over the lanes) a few percent, a texel-buffer fetch of 8 bits a loop too, one of
// 32 bits a single gather (docs/BENCHMARKS.md).
uint march_voxel(vec3 x) {
    ivec3 size = slab_size();
    vec3 u = (x - BOX_MIN) / (BOX_MAX - BOX_MIN) * vec3(size);
    if ((MATERIALS == 0u && LEAPS == 0u) || any(lessThan(u, vec3(0.0))) || any(greaterThanEqual(u, vec3(size)))) return MARCH_OUTSIDE;
    ivec3 q = ivec3(u);
    return texelFetch(march_texels, q.x + size.x * (q.y + size.y * q.z)).r;
}
// The boundary band's reflectance factor (the CPU spreads each surface's factor over its
// band), -1 outside the band and the box.
float band_factor_of(uint bits) {
    return MATERIALS != 0u ? uintBitsToFloat(bits & ~0xffu) : -1.0;
}

// How far the ray at x with unit direction d stays where every field sample has |grad n| at
// most the weak-gradient threshold per voxel edge (0 with no threshold): in the cube of the
// weak-gradient map around x (`bits`, x's march voxel), less half a voxel on each side, where
// a trilinear lookup reads the cube's voxels only (a cube of one voxel has no such inside).
float weak_length(vec3 x, vec3 d, uint bits) {
    int k = int(bits & 0xffu);
    vec3 cell = (BOX_MAX - BOX_MIN) / vec3(slab_size());
    return k < 2 ? 0.0 : cube_exit(x, d, BOX_MIN, BOX_MAX, march_cell(x), k, cell, 0.5);
}

// ---- material lookups ----
// Trilinear interpolation of a material volume (clamped to the box's voxels).
vec4 sample_material(sampler3D map, vec3 x) {
    ivec3 size = textureSize(map, 0);
    vec3 u = clamp((x - BOX_MIN) / (BOX_MAX - BOX_MIN) * vec3(size) - 0.5, vec3(0.0), vec3(size - 1));
    ivec3 i = ivec3(floor(u));
    ivec3 j = min(i + 1, size - 1);
    vec3 f = u - vec3(i);
    vec4 c00 = mix(texelFetch(map, i, 0), texelFetch(map, ivec3(j.x, i.y, i.z), 0), f.x);
    vec4 c10 = mix(texelFetch(map, ivec3(i.x, j.y, i.z), 0), texelFetch(map, ivec3(j.x, j.y, i.z), 0), f.x);
    vec4 c01 = mix(texelFetch(map, ivec3(i.x, i.y, j.z), 0), texelFetch(map, ivec3(j.x, i.y, j.z), 0), f.x);
    vec4 c11 = mix(texelFetch(map, ivec3(i.x, j.y, j.z), 0), texelFetch(map, j, 0), f.x);
    return mix(mix(c00, c10, f.y), mix(c01, c11, f.y), f.z);
}
// ---- end of the material volumes ----

// Slab test; (t_near, t_far) with t_near > t_far on a miss.
vec2 ray_box(vec3 o, vec3 d) {
    vec3 inv = 1.0 / mix(vec3(1e-30), d, greaterThan(abs(d), vec3(1e-30)));
    vec3 t0 = (BOX_MIN - o) * inv, t1 = (BOX_MAX - o) * inv;
    vec3 lo = min(t0, t1), hi = max(t0, t1);
    return vec2(max(max(lo.x, lo.y), lo.z), min(min(hi.x, hi.y), hi.z));
}

bool in_box(vec3 x, float margin) {
    return all(greaterThanEqual(x, BOX_MIN - margin)) && all(lessThanEqual(x, BOX_MAX + margin));
}


// ---- one march through index slab `c` (all of RGB when CHANNELS = 1) ----
// Fresnel at a boundary (Eq. 2's delta rho L_r with T of Eq. 5). Inside the band of the
// boundary indicator the smoothed index crosses a jump; the march splits the index along
// the path into monotone runs (a thin layer such as a glass wall, or two faces whose bands
// merge, is two runs: up, then down). At the end of a run (the index turns back, or the
// band ends) the jump n_a -> n_peak is known; the normal is the direction of grad n summed
// over the run. The reflected fraction F (exact Fresnel for unpolarised light, times the
// region's reflectance factor) looks up the environment in the mirror direction, weighted
// by the transmittance where the run began; the march carries 1 - F. A ray that the ray
// equation turned back inside the band (total internal reflection, section 4.1) has been
// reflected already: neither its turning run nor the run back out adds a reflection.
struct Run {
    float n_a, n_peak, rho;
    vec3 d_a, grad_sum, T_a;
    bool turned;
};

// What the march's rays meet outside the box is shaded after the march, not where it is
// found: a CPU device (lavapipe) runs the code of every branch of the loop's body in every
// step with the lanes that do not take it masked, and exit_radiance (the triangles, the
// impostors, the receiver's light) inside the loop cost two evaluations per step of every
// ray, 3x the whole march on eikonal_sphere (docs/BENCHMARKS.md). The reflected rays of the
// Fresnel events (at most MAX_REFLECTIONS per march: a ray with more loses the later ones'
// reflected light; at 96^2 the bundled scenes' rays have at most 33 to 64, on
// eikonal_dispersion_cube, and the images are the same as with the events shaded where they
// are found), then the exit ray or the receiver that the march hit inside the box.
// The lanes of a SIMD group store at different indices, which a CPU device does lane by
// lane, in every step: so a step holds its event (at most one) in `pending` and stores it
// at one place, the end of the step.
const uint MAX_REFLECTIONS = 64u;
vec3 reflection_origin[MAX_REFLECTIONS];
vec3 reflection_dir[MAX_REFLECTIONS];
vec3 reflection_weight[MAX_REFLECTIONS];
uint reflections;

struct Reflection {
    bool pending;
    vec3 origin, dir, weight;
};
Reflection pending;

void add_reflection(vec3 x, vec3 dir, vec3 weight) {
    pending = Reflection(true, x, dir, weight);
}

void store_pending() {
    if (pending.pending && reflections < MAX_REFLECTIONS) {
        reflection_origin[reflections] = pending.origin;
        reflection_dir[reflections] = pending.dir;
        reflection_weight[reflections] = pending.weight;
        reflections += 1u;
    }
    pending.pending = false;
}

void run_start(inout Run r, float n, vec3 v, vec3 T) {
    r.n_a = n;
    r.n_peak = n;
    r.d_a = normalize(v);
    r.grad_sum = vec3(0.0);
    r.T_a = T;
    r.rho = 0.0;
}

// The Fresnel event at the end of run r; v is the ray's current optical direction, x its
// position (where the reflected ray starts towards the nearby geometry, shaded after the
// march: add_reflection).
void run_end(inout Run r, vec3 x, vec3 v, inout vec3 T) {
    vec3 N = dot(r.grad_sum, r.grad_sum) > 1e-20 ? normalize(r.grad_sum) : -r.d_a;
    bool crossed = dot(normalize(v), N) * dot(r.d_a, N) > 0.0;
    if (!crossed || r.turned) {
        r.turned = !crossed;
        return;
    }
    float F = r.rho * fresnel_dielectric(abs(dot(r.d_a, N)), r.n_a / max(r.n_peak, 1e-3));
    F = clamp(F, 0.0, 1.0);
    add_reflection(x, reflect(r.d_a, N), r.T_a * F);
    T *= 1.0 - F;
}

vec3 march(vec3 o, vec3 d, float t_enter, int c, inout bool touched) {
    vec3 x = o + d * t_enter;
    // The field at x: the next step's first stage (the previous step's end sample).
    vec4 s = sample_field(x, c);
    float n_cur = 1.0 + s.w;
    vec3 v = d * n_cur;  // |v| = n: v is the ray's optical direction
    vec3 T = vec3(1.0), L = vec3(0.0);
    // A ray that enters the box inside a band comes from the air (n = 1).
    Run r;
    r.turned = false;
    // The march map at x: read once per step, at its end, for this step and the next (the
    // band's factor, -1 outside, and the reach of the merged steps).
    uint x_bits = march_voxel(x);
    float x_factor = band_factor_of(x_bits);
    bool x_band = x_factor >= 0.0;
    bool banded = x_band;
    run_start(r, 1.0, d, T);
    if (banded) r.rho = x_factor;
    // Rays that leave the box stop one step past its face at most.
    float margin = STEP;
    // The last point inside the box proper, where the exit ray starts.
    vec3 x_in = x;
    reflections = 0u;
    pending.pending = false;
    // A receiver inside the box that the march hit: triangle k at o + t dir, barycentrics b.
    bool hit = false;
    // Stopped by MIN_TRANSMITTANCE: nothing beyond the last step is added.
    bool opaque = false;
    uint hit_k = 0u;
    vec3 hit_o = vec3(0.0), hit_dir = vec3(0.0);
    float hit_t = 0.0;
    vec2 hit_b = vec2(0.0);
    for (uint i = 0u; i <= MAX_STEPS; ++i) {
        bool inside = i < MAX_STEPS && in_box(x, margin);
        bool band = inside && x_band;
        if (banded && !band) {
            // Leaving the band (into the air beyond the box when outside it).
            if (!inside && abs(1.0 - r.n_a) > abs(r.n_peak - r.n_a)) r.n_peak = 1.0;
            banded = false;
            run_end(r, x, v, T);
            r.turned = false;
        }
        if (!inside) break;
        if (band && !banded) {
            banded = true;
            r.turned = false;
            run_start(r, n_cur, v, T);
        }
        // Merged steps (LEAPS): where every field sample within reach of x is weak (the
        // weak-gradient map), m whole steps are integrated as one of m STEP, and the march goes
        // on with the same step count. Where the index is constant there (a uniform region:
        // the air in the box, the inside of a constant-index object) every stage of a step sees
        // the same (0, n - 1) and the merged step is the full march's straight line exactly;
        // elsewhere the ray turns by less than the map's threshold per voxel travelled.
        vec3 x0 = x;
        float h = STEP;
        if (LEAPS != 0u) {
            float m = min(floor(weak_length(x, normalize(v), x_bits) / STEP), float(MAX_STEPS - i));
            if (m >= 2.0) {
                h = m * STEP;
                i += uint(m) - 1u;
            }
        }
        // Verlet's parameter step: d tau = ds / n, so that a step of tau = h / n moves about h
        // of arc length (|v| = n).
        float tau = h / max(n_cur, 1e-3);
        if (INTEGRATOR == EIKONAL_RK4) {
            vec3 k1x, k1v, k2x, k2v, k3x, k3v, k4x, k4v;
            rhs_at(s, v, k1x, k1v);
            rhs(x + 0.5 * h * k1x, v + 0.5 * h * k1v, c, k2x, k2v);
            rhs(x + 0.5 * h * k2x, v + 0.5 * h * k2v, c, k3x, k3v);
            rhs(x + h * k3x, v + h * k3v, c, k4x, k4v);
            x += h / 6.0 * (k1x + 2.0 * k2x + 2.0 * k3x + k4x);
            v += h / 6.0 * (k1v + 2.0 * k2v + 2.0 * k3v + k4v);
        } else if (INTEGRATOR == EIKONAL_VERLET) {
            // Eqs. 9-10 in tau (d tau = ds / n: dx/d tau = v, dv/d tau = n grad n) by
            // velocity Verlet: a half kick with a(x) = n grad n and the drift here, the
            // second half kick with the end sample below.
            v += (0.5 * tau * (1.0 + s.w)) * s.xyz;
            x += tau * v;
        } else if (INTEGRATOR == EIKONAL_MIDPOINT) {
            // Second order: the slope at the half step's Euler estimate.
            vec3 k1x, k1v, k2x, k2v;
            rhs_at(s, v, k1x, k1v);
            rhs(x + 0.5 * h * k1x, v + 0.5 * h * k1v, c, k2x, k2v);
            x += h * k2x;
            v += h * k2v;
        } else {
            // Eqs. 11-12.
            vec3 dx, dv;
            rhs_at(s, v, dx, dv);
            x += h * dx;
            v += h * dv;
        }
        s = sample_field(x, c);
        n_cur = 1.0 + s.w;
        if (INTEGRATOR == EIKONAL_VERLET) v += (0.5 * tau * n_cur) * s.xyz;
        x_bits = march_voxel(x);
        x_factor = band_factor_of(x_bits);
        x_band = x_factor >= 0.0;
        touched = touched || abs(s.w) > 1e-4;
        // ---- a receiver inside (or touching) the box ends the path where the
        // step's chord crosses it (e.g. the table a wine glass stands on).
        if (TRIANGLES_IN_BOX != 0u) {
            vec3 seg = x - x0;
            float len = length(seg);
            float t_hit;
            uint k;
            vec2 b;
            if (len > 0.0 && eik_triangle_hit(x0, seg / len, 0.0, len, t_hit, k, b)) {
                hit = true;
                hit_k = k;
                hit_o = x0;
                hit_dir = seg / len;
                hit_t = t_hit;
                hit_b = b;
                break;
            }
        }
        if (in_box(x, 0.0)) x_in = x;
        // ---- end of the receiver inside the box
        if (banded) {
            float up = r.n_peak - r.n_a;
            if (up * (n_cur - r.n_peak) < 0.0 && abs(n_cur - r.n_peak) > 0.02 * abs(up) + 1e-4) {
                // The index turns back: the run ends at its peak, a new one begins.
                run_end(r, x, v, T);
                float peak = r.n_peak;
                run_start(r, peak, v, T);
            }
            if (abs(n_cur - r.n_a) > abs(r.n_peak - r.n_a)) r.n_peak = n_cur;
            r.grad_sum += s.xyz;
            // Only band voxels carry their surface's factor (the step may have left the band).
            if (x_band) r.rho = max(r.rho, x_factor);
        }
        if (EXTINCTION != 0u || EMISSION != 0u) {
            vec3 mid = 0.5 * (x0 + x);
            if (in_box(mid, 0.0)) {
                // Eq. 1 over one segment of length len with constant extinction sigma and
                // emission E: int_0^len E e^{-sigma s} ds = E (1 - e^{-sigma len}) / sigma
                // (E len where sigma len is tiny); then Eq. 5's e^{-sigma len}.
                float len = distance(x0, x);
                vec4 ext = EXTINCTION != 0u ? sample_material(extinction_map, mid) : vec4(0.0);
                vec3 sigma = ext.rgb;
                vec3 E = EMISSION != 0u ? sample_material(emission_map, mid).rgb : vec3(0.0);
                vec3 tau = sigma * len;
                vec3 trans = exp(-tau);
                vec3 path = mix(vec3(len), (1.0 - trans) / max(sigma, vec3(1e-30)), greaterThan(tau, vec3(1e-4)));
                L += T * E * path;
                // ---- Eq. 1's in-scattering T sigma_s p dE_omega (Eq. 6)
                // over the segment, with sigma_s = albedo * extinction and g from the
                // material volumes; constant over the segment like E.
                if (SCATTER != 0u && EXTINCTION != 0u) {
                    vec3 sigma_s = sample_material(albedo_map, mid).rgb * ext.rgb;
                    if (any(greaterThan(sigma_s, vec3(0.0)))) {
                        vec3 light_min = vec3(LIGHT_MIN_X, LIGHT_MIN_Y, LIGHT_MIN_Z);
                        vec3 light_max = vec3(LIGHT_MAX_X, LIGHT_MAX_Y, LIGHT_MAX_Z);
                        L += T * sigma_s * path * inscatter(mid, -normalize(x - x0), light_min, light_max, ext.a);
                    }
                }
                touched = touched || any(greaterThan(sigma, vec3(0.0))) || any(greaterThan(E, vec3(0.0)));
                T *= trans;
            }
        }
        // A step's one event: where it leaves a band (the top) or where the index turns
        // (above), never both, since leaving the band ends the banded part of the step.
        store_pending();
        // Early ray termination: whatever lies beyond adds at most MIN_TRANSMITTANCE of its
        // radiance. A dispersive march carries only its own channel. Not inside a Fresnel
        // run: its reflection is weighted by the transmittance where the run began, and is
        // only recorded where the run ends (a dense glass reflects F of what reaches it
        // however quickly it absorbs what enters).
        float T_carried = CHANNELS == 3u ? T[c] : max(T.r, max(T.g, T.b));
        if (T_carried < MIN_TRANSMITTANCE && !banded) {
            opaque = true;
            break;
        }
    }
    // The event of the step that left the box or hit a receiver.
    store_pending();
    for (uint k = 0u; k < reflections; ++k) {
        L += reflection_weight[k] * exit_radiance(reflection_origin[k], reflection_dir[k], 0.0);
    }
    if (opaque) return L;
    if (hit) return L + T * eik_triangle_radiance(hit_k, hit_o, hit_dir, hit_t, hit_b);
    // A degenerate momentum (never for n > 0) keeps the incoming direction.
    vec3 exit_dir = dot(v, v) > 1e-20 ? normalize(v) : d;
    // The exit ray from the last point inside the box meets the nearby geometry
    // (a hit a hair behind that point counts: a floor the box stands on).
    return L + T * exit_radiance(x_in, exit_dir, -1e-4);
}
// ---- end of the material volumes ----

void main() {
    vec3 o = frame.camera_position.xyz;
    vec3 d = camera_ray(in_uv);
    vec2 t = ray_box(o, d);
    if (t.x > t.y || t.y < 0.0) discard;
    float t_enter = max(t.x, 0.0);
    // Geometry in front of the volume hides it.
    float depth = texelFetch(gbuf_depth, ivec2(gl_FragCoord.xy), 0).r;
    if (depth > 0.0 && distance(world_from_depth(in_uv, depth), o) < t_enter) discard;

    vec3 L;
    bool touched = false;
    if (CHANNELS == 3u) {
        // Dispersion (section 5.3): each channel follows its own index field.
        for (int c = 0; c < 3; ++c) L[c] = march(o, d, t_enter, c, touched)[c];
    } else {
        L = march(o, d, t_enter, 0, touched);
    }
    // ---- a ray that crossed only air (no index change, extinction or
    // emission) keeps what deferred shading drew behind it (e.g. the floor under the volume,
    // lit by the simulated light) instead of the environment.
    if (!touched) discard;
    out_radiance = vec4(finite_or_zero(L), 1.0);
}
