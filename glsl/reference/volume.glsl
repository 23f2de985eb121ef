// The reference's graded-index volume (src/reference/mod.rs, module doc; Ihrke et al. 2007,
// Eqs. 9-10 integrated by classical RK4 with a small step). The region is the profile's
// sphere or the volume's box; outside it n = 1. At the region's boundary the index may jump
// (a constant or linear profile): there the path reflects with probability F (exact
// Fresnel) or refracts (Snell), like specular_step. Inside, the analytic profile's ray
// equation is integrated exactly enough to serve as ground truth for the view renderer.
#ifndef PRISM_REFERENCE_VOLUME_GLSL
#define PRISM_REFERENCE_VOLUME_GLSL
#include "scene.glsl"

// ref.volume rows: [0] box min, kind; [1] box max, RK4 step; [2] region centre, radius
// (0: the box); [3] profile (Luneburg: centre, R; linear: gradient, n0; constant: -, n);
// [4] sigma_a rgb, most steps.
const uint VOLUME_NONE = 0u, VOLUME_LUNEBURG = 1u, VOLUME_LINEAR = 2u, VOLUME_CONSTANT = 3u;
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
bool volume_cross(inout vec3 o, inout vec3 d, float t, inout vec3 beta, inout uint rng) {
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
    for (uint i = 0u; i < steps; ++i) {
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
    return false;
}
#endif
