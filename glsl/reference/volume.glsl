// The reference's graded-index volume (src/reference/mod.rs, module doc; Ihrke et al. 2007,
// Eqs. 9-10 integrated by classical RK4 with a small step). The region is the profile's
// sphere or the volume's box; outside it n = 1. At the region's boundary the index may jump
// (a constant or linear profile): there the path reflects with probability F (exact
// Fresnel) or refracts (Snell), like specular_step. Inside, the analytic profile's ray
// equation is integrated exactly enough to serve as ground truth for the view renderer.
#ifndef PRISM_REFERENCE_VOLUME_GLSL
#define PRISM_REFERENCE_VOLUME_GLSL
#include "trace.glsl"

// Where a path ends inside the volume because it took `steps` steps (ref.volume[4].w): the
// reference's kernels count those (glsl/reference/sppm.glsl); the raytrace technique does not.
#ifndef VOLUME_STEP_CAP_REACHED
#define VOLUME_STEP_CAP_REACHED()
#endif

// 3 vec4 per voxel (VOLUME_FIELDS; a one-element stand-in otherwise).
layout(set = REF_SET, binding = REF_BINDING_VOLUME, std430) readonly buffer VolumeVoxels { vec4 volume_voxels[]; };

// ref.volume rows: [0] box min, kind; [1] box max, RK4 step; [2] region centre, radius
// (0: the box); [3] profile (Luneburg: centre, R; linear: gradient, n0; constant: -, n);
// [4] sigma_a rgb, most steps; [5] (VOLUME_FIELDS only) -, voxels along x, y, z.
const uint VOLUME_NONE = 0u, VOLUME_LUNEBURG = 1u, VOLUME_LINEAR = 2u, VOLUME_CONSTANT = 3u;
// A volume with `[[volume.region]]`s is traced through the same voxel
// fields the view renderer gets (src/scene/volume_sources.rs), see volume_cross_fields.
const uint VOLUME_FIELDS = 4u;
uint volume_kind() { return uint(ref.volume[0].w + 0.5); }

// Ray offset at the region's boundary: the scene's epsilon, or 1e-5 of the box diagonal when
// that is larger (a scene with only a volume has no surfaces to give it a size).
float volume_eps() { return max(ref.proj.z, 1e-5 * distance(ref.volume[0].xyz, ref.volume[1].xyz)); }

float volume_n(vec3 x) {
    vec4 p = ref.volume[3];
    uint k = volume_kind();
    if (k == VOLUME_LUNEBURG) return sqrt(2.0 - min(dot(x - p.xyz, x - p.xyz) / (p.w * p.w), 1.0));
    if (k == VOLUME_LINEAR) return p.w + dot(p.xyz, x - 0.5 * (ref.volume[0].xyz + ref.volume[1].xyz));
    return p.w;
}

vec3 volume_grad(vec3 x) {
    vec4 p = ref.volume[3];
    uint k = volume_kind();
    if (k == VOLUME_LUNEBURG) {
        vec3 d = x - p.xyz;
        return dot(d, d) <= p.w * p.w ? -d / (p.w * p.w * volume_n(x)) : vec3(0.0);
    }
    if (k == VOLUME_LINEAR) return p.xyz;
    return vec3(0.0);
}

bool in_region(vec3 x) {
    vec4 r = ref.volume[2];
    if (r.w > 0.0) return distance(x, r.xyz) < r.w;
    return all(greaterThan(x, ref.volume[0].xyz)) && all(lessThan(x, ref.volume[1].xyz));
}

// Outward unit normal of the region's boundary nearest x.
vec3 region_normal(vec3 x) {
    vec4 r = ref.volume[2];
    if (r.w > 0.0) return normalize(x - r.xyz);
    vec3 c = 0.5 * (ref.volume[0].xyz + ref.volume[1].xyz), e = 0.5 * (ref.volume[1].xyz - ref.volume[0].xyz);
    vec3 q = abs(x - c) / e;
    vec3 n = vec3(0.0);
    int a = q.x > q.y ? (q.x > q.z ? 0 : 2) : (q.y > q.z ? 1 : 2);
    n[a] = sign(x[a] - c[a]);
    return n;
}

// Distance along d (unit) at which a ray from o, outside, enters the region; false if not.
bool region_entry(vec3 o, vec3 d, float t_max, out float t) {
    t = 0.0;
    if (volume_kind() == VOLUME_NONE) return false;
    vec4 r = ref.volume[2];
    float eps = volume_eps();
    if (r.w > 0.0) return intersect_sphere(o, d, r, eps, t_max, t);
    vec3 inv = 1.0 / mix(vec3(1e-30), d, greaterThan(abs(d), vec3(1e-30)));
    vec3 t0 = (ref.volume[0].xyz - o) * inv, t1 = (ref.volume[1].xyz - o) * inv;
    float near = max(max(min(t0.x, t1.x), min(t0.y, t1.y)), min(t0.z, t1.z));
    float far = min(min(max(t0.x, t1.x), max(t0.y, t1.y)), max(t0.z, t1.z));
    t = near;
    return near > eps && near <= far && near < t_max;
}

// One RK4 step of arc length h of Eqs. 9-10.
void volume_rk4(inout vec3 x, inout vec3 v, float h) {
    vec3 k1x = v / volume_n(x), k1v = volume_grad(x);
    vec3 x2 = x + 0.5 * h * k1x, v2 = v + 0.5 * h * k1v;
    vec3 k2x = v2 / volume_n(x2), k2v = volume_grad(x2);
    vec3 x3 = x + 0.5 * h * k2x, v3 = v + 0.5 * h * k2v;
    vec3 k3x = v3 / volume_n(x3), k3v = volume_grad(x3);
    vec3 x4 = x + h * k3x, v4 = v + h * k3v;
    vec3 k4x = v4 / volume_n(x4), k4v = volume_grad(x4);
    x += h / 6.0 * (k1x + 2.0 * k2x + 2.0 * k3x + k4x);
    v += h / 6.0 * (k1v + 2.0 * k2v + 2.0 * k3v + k4v);
}

// The path at o heading along d enters the region at distance t: cross it. On return o and
// d continue the path outside (reflected at the entry, or out of the far side) and beta
// holds the absorption; false if the path ends inside (too many steps).
bool volume_cross_fields(inout vec3 o, inout vec3 d, float t, inout vec3 beta, inout vec3 L, int channel,
                         inout uint rng);

bool volume_cross(inout vec3 o, inout vec3 d, float t, inout vec3 beta, inout vec3 L, int channel, inout uint rng) {
    if (volume_kind() == VOLUME_FIELDS) return volume_cross_fields(o, d, t, beta, L, channel, rng);
    float eps = volume_eps();
    vec3 x = o + t * d;
    vec3 N = region_normal(x);
    float n_in = volume_n(x - eps * N);
    float F = fresnel_dielectric(-dot(d, N), 1.0 / n_in);
    if (rand(rng) < F) {
        o = x + eps * N;
        d = reflect(d, N);
        return true;
    }
    vec3 v = n_in * normalize(refract(d, N, 1.0 / n_in));
    x -= eps * N;
    float h = ref.volume[1].w;
    vec3 sigma = ref.volume[4].xyz;
    uint steps = uint(ref.volume[4].w);
    uint i = 0u;
    for (; i < steps; ++i) {
        vec3 x1 = x, v1 = v;
        volume_rk4(x1, v1, h);
        if (in_region(x1)) {
            beta *= exp(-sigma * distance(x, x1));
            x = x1;
            v = v1;
            continue;
        }
        // The step leaves the region: bisect the step length for the boundary.
        float lo = 0.0, hi = h;
        for (int b = 0; b < 24; ++b) {
            float mid = 0.5 * (lo + hi);
            vec3 xm = x, vm = v;
            volume_rk4(xm, vm, mid);
            if (in_region(xm)) lo = mid; else hi = mid;
        }
        vec3 xb = x, vb = v;
        volume_rk4(xb, vb, lo);
        beta *= exp(-sigma * distance(x, xb));
        vec3 Nb = region_normal(xb);
        vec3 dir = normalize(vb);
        float n_b = volume_n(xb - eps * Nb);
        float Fb = fresnel_dielectric(dot(dir, Nb), n_b);   // 1 under total internal reflection
        if (rand(rng) < Fb) {
            dir = reflect(dir, Nb);
            x = xb - eps * Nb;
            v = n_b * dir;
            continue;
        }
        o = xb + eps * Nb;
        d = normalize(refract(dir, -Nb, n_b));
        return true;
    }
    // The loop also ends early where the driver's loop budget ran out (loop_canary).
    if (i >= steps) VOLUME_STEP_CAP_REACHED();
    return false;
}
// ---- the voxel fields (volumes with regions) ----
// The reference for a volume built from sources integrates the ray equation by RK4 with
// small steps through the same rasterized fields as the view renderer (the index per
// channel, the extinction, the emission), but *unsmoothed* (trilinear over the one-voxel
// coverage ramps of the sources) and with the exact gradient of the trilinear interpolant;
// at every crossing of an index jump (the boundary indicator widened by one voxel, the ramp)
// it reflects with probability F (exact Fresnel times the region's reflectance, for the
// jump from the index before the band to the one after it) and goes on marching the
// reflected path inside the volume (multiple internal reflections), unlike the view
// renderer's single environment lookup. Dispersive volumes trace one channel per path.
// Scattering (sigma_s) only attenuates here (the light branch adds in-scattering), and
// emission is added on camera paths only.
ivec3 field_res() { return ivec3(ref.volume[5].yzw + 0.5); }

// Voxel q's k-th vec4: 0 (n - 1 RGB, boundary band), 1 (extinction RGB, -), 2 (emission
// RGB, reflectance); beyond the box air (zero).
vec4 field_voxel(ivec3 q, int k) {
    ivec3 r = field_res();
    if (any(lessThan(q, ivec3(0))) || any(greaterThanEqual(q, r))) return vec4(0.0);
    return volume_voxels[3 * (q.x + r.x * (q.y + r.y * q.z)) + k];
}

// Trilinear interpolation of component c of vec4 k at x, and its exact gradient.
float field_lerp(vec3 x, int k, int c, out vec3 grad) {
    ivec3 r = field_res();
    vec3 scale = vec3(r) / (ref.volume[1].xyz - ref.volume[0].xyz);
    vec3 u = clamp((x - ref.volume[0].xyz) * scale - 0.5, vec3(-1.0), vec3(r));
    ivec3 i = ivec3(floor(u));
    vec3 f = u - vec3(i);
    float v[8];
    for (int n = 0; n < 8; ++n) v[n] = field_voxel(i + ivec3(n & 1, (n >> 1) & 1, (n >> 2) & 1), k)[c];
    float x00 = mix(v[0], v[1], f.x), x10 = mix(v[2], v[3], f.x), x01 = mix(v[4], v[5], f.x), x11 = mix(v[6], v[7], f.x);
    float y0 = mix(x00, x10, f.y), y1 = mix(x01, x11, f.y);
    grad.x = mix(mix(v[1] - v[0], v[3] - v[2], f.y), mix(v[5] - v[4], v[7] - v[6], f.y), f.z);
    grad.y = mix(x10 - x00, x11 - x01, f.z);
    grad.z = y1 - y0;
    grad *= scale;
    return mix(y0, y1, f.z);
}

vec3 field_rgb(vec3 x, int k) {
    vec3 g;
    return vec3(field_lerp(x, k, 0, g), field_lerp(x, k, 1, g), field_lerp(x, k, 2, g));
}

bool field_band(vec3 x) {
    ivec3 r = field_res();
    vec3 u = (x - ref.volume[0].xyz) / (ref.volume[1].xyz - ref.volume[0].xyz) * vec3(r);
    return field_voxel(ivec3(floor(u)), 0).w > 0.5;
}

// The band's reflectance factor (nearest voxel, spread over the band on the CPU).
float field_reflectance(vec3 x) {
    ivec3 r = field_res();
    vec3 u = (x - ref.volume[0].xyz) / (ref.volume[1].xyz - ref.volume[0].xyz) * vec3(r);
    return field_voxel(clamp(ivec3(floor(u)), ivec3(0), r - 1), 2).w;
}

// One RK4 step of Eqs. 9-10 through channel c's field.
void field_rk4(inout vec3 x, inout vec3 v, float h, int c) {
    vec3 g1, g2, g3, g4;
    float n1 = 1.0 + field_lerp(x, 0, c, g1);
    vec3 k1x = v / max(n1, 1e-3);
    vec3 x2 = x + 0.5 * h * k1x, v2 = v + 0.5 * h * g1;
    float n2 = 1.0 + field_lerp(x2, 0, c, g2);
    vec3 k2x = v2 / max(n2, 1e-3);
    vec3 x3 = x + 0.5 * h * k2x, v3 = v + 0.5 * h * g2;
    float n3 = 1.0 + field_lerp(x3, 0, c, g3);
    vec3 k3x = v3 / max(n3, 1e-3);
    vec3 x4 = x + h * k3x, v4 = v + h * g3;
    float n4 = 1.0 + field_lerp(x4, 0, c, g4);
    vec3 k4x = v4 / max(n4, 1e-3);
    x += h / 6.0 * (k1x + 2.0 * k2x + 2.0 * k3x + k4x);
    v += h / 6.0 * (g1 + 2.0 * g2 + 2.0 * g3 + g4);
}

bool in_box_closed(vec3 x) {
    return all(greaterThanEqual(x, ref.volume[0].xyz)) && all(lessThanEqual(x, ref.volume[1].xyz));
}

// The path at o heading along d enters the box at distance t: cross it (see above). L
// gathers the emission seen along the path. Index jumps are found as in the view renderer
// (glsl/eikonal/view.frag, `Run`): the index inside a band is split into monotone runs, and
// the Fresnel event of a run is decided where it ends, with the normal from grad n summed
// over the run; a reflected path restarts where its run began.
bool volume_cross_fields(inout vec3 o, inout vec3 d, float t, inout vec3 beta, inout vec3 L, int channel,
                         inout uint rng) {
    int c = max(channel, 0);
    float eps = volume_eps();
    // Start just inside the box (its face may round to either side).
    vec3 x = o + (t + eps) * d, g;
    float n = 1.0 + field_lerp(x, 0, c, g);
    vec3 v = n * d;
    float h = ref.volume[1].w;
    uint steps = uint(ref.volume[4].w);
    // The run state; a path entering the box inside a band comes from the air.
    bool banded = field_band(x), turned = false;
    float n_a = 1.0, n_peak = 1.0, rho = banded ? field_reflectance(x) : 0.0;
    vec3 x_a = x - eps * d, d_a = d, grad_sum = vec3(0.0), x_prev = x - eps * d, beta_a = beta;
    uint i = 0u;
    for (; i < steps; ++i) {
        bool inside = in_box_closed(x);
        bool band = inside && field_band(x);
        bool turn = false;
        if (banded && inside) {
            float up = n_peak - n_a;
            turn = up * (n - n_peak) < 0.0 && abs(n - n_peak) > 0.02 * abs(up) + 1e-4;
        }
        if (banded && (!band || turn)) {
            // The end of a run: its Fresnel event.
            if (!inside && abs(1.0 - n_a) > abs(n_peak - n_a)) n_peak = 1.0;
            vec3 N = dot(grad_sum, grad_sum) > 1e-20 ? normalize(grad_sum) : -d_a;
            bool crossed = dot(normalize(v), N) * dot(d_a, N) > 0.0;
            bool skip = !crossed || turned;
            turned = !crossed;
            if (!skip) {
                float F = clamp(rho * fresnel_dielectric(abs(dot(d_a, N)), n_a / max(n_peak, 1e-3)), 0.0, 1.0);
                if (rand(rng) < F) {
                    // Reflect where the run began (with the throughput it had there: the
                    // reflected path never entered the medium beyond), and march on.
                    x = x_a;
                    beta = beta_a;
                    n = n_a;
                    v = n_a * reflect(d_a, N);
                    banded = field_band(x);
                    turned = false;
                    n_peak = n_a;
                    d_a = normalize(v);
                    grad_sum = vec3(0.0);
                    rho = 0.0;
                    x_prev = x;
                    continue;
                }
            }
            if (!band) {
                banded = false;
                turned = false;
            } else {
                // A new run from the peak.
                n_a = n_peak;
                n_peak = n;
                x_a = x;
                beta_a = beta;
                d_a = normalize(v);
                grad_sum = vec3(0.0);
                rho = 0.0;
            }
        }
        if (!inside) {
            o = x;
            d = normalize(v);
            return true;
        }
        if (band && !banded) {
            banded = true;
            turned = false;
            n_a = n;
            n_peak = n;
            x_a = x_prev;
            beta_a = beta;
            d_a = normalize(v);
            grad_sum = vec3(0.0);
            rho = 0.0;
        }
        x_prev = x;
        field_rk4(x, v, h, c);
        n = 1.0 + field_lerp(x, 0, c, g);
        if (banded) {
            if (abs(n - n_a) > abs(n_peak - n_a)) n_peak = n;
            grad_sum += g;
            if (field_band(x)) rho = max(rho, field_reflectance(x));
        }
        // Eq. 1 and Eq. 5 over the segment (constant coefficients at its midpoint).
        vec3 mid = 0.5 * (x_prev + x);
        if (in_box_closed(mid)) {
            float len = distance(x_prev, x);
            vec3 sigma = field_rgb(mid, 1), E = field_rgb(mid, 2);
            vec3 tau = sigma * len, trans = exp(-tau);
            vec3 path = mix(vec3(len), (1.0 - trans) / max(sigma, vec3(1e-30)), greaterThan(tau, vec3(1e-4)));
            L += beta * E * path;
            beta *= trans;
        }
    }
    // The loop also ends early where the driver's loop budget ran out (loop_canary).
    if (i >= steps) VOLUME_STEP_CAP_REACHED();
    return false;
}
// ---- end of the material volumes ----
#endif
