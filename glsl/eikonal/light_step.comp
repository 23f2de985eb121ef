#version 450
// One step of the eikonal light simulator for every patch (Ihrke et al. 2007):
// - section 5.2.1: advance the four corners by the equal-time ray equation, Eqs. 14-15
//   (dx/dt = v / n^2, dv/dt = grad n / n; forward Euler like the paper, or RK4), so that all
//   particles stay on one wavefront (Appendix, Eqs. 23-24: dS/dt = 1);
// - Eq. 18: the flux dE * A loses exp(-sigma_r dt / n) (ds = dt / n, Eq. 24); without
//   absorption it is constant, and the irradiance is flux / area (Eq. 17);
// - section 5.2.2: voxelize the patch midpoint, keeping per voxel the highest-energy ray
//   (first half of a two-pass scheme: atomicMax of the irradiance's float bits, which order
//   like the floats for non-negative values; light_deposit.comp then lets the winner write);
// - section 5.2.3: classify it 0 (eliminate: below the energy threshold, leaving the volume,
//   or its orientation flipped against its direction = it crossed a wavefront singularity),
//   1 (retain) or 4 (tessellate: its corners span more than one voxel along an axis).
#include "light_common.glsl"
layout(local_size_x = LIGHT_GROUP) in;

void rhs(vec3 x, vec3 v, out vec3 dx, out vec3 dv) {
    vec4 f = sample_field(x);
    float n = max(1.0 + f.w, 1e-3);
    dx = v / (n * n);   // Eq. 14
    dv = f.xyz / n;     // Eq. 15
}

void advance(inout vec3 x, inout vec3 v) {
    float h = DT;
    if (INTEGRATOR == EIKONAL_RK4) {
        vec3 k1x, k1v, k2x, k2v, k3x, k3v, k4x, k4v;
        rhs(x, v, k1x, k1v);
        rhs(x + 0.5 * h * k1x, v + 0.5 * h * k1v, k2x, k2v);
        rhs(x + 0.5 * h * k2x, v + 0.5 * h * k2v, k3x, k3v);
        rhs(x + h * k3x, v + h * k3v, k4x, k4v);
        x += h / 6.0 * (k1x + 2.0 * k2x + 2.0 * k3x + k4x);
        v += h / 6.0 * (k1v + 2.0 * k2v + 2.0 * k3v + k4v);
    } else {
        vec3 dx, dv;
        rhs(x, v, dx, dv);
        x += h * dx;
        v += h * dv;
    }
}

// Does the straight ray (outside the medium n = 1) from o along d still reach the box?
bool heads_into_box(vec3 o, vec3 d) {
    vec3 inv = 1.0 / mix(vec3(1e-30), d, greaterThan(abs(d), vec3(1e-30)));
    vec3 t0 = (LIGHT_MIN - o) * inv, t1 = (LIGHT_MAX - o) * inv;
    vec3 lo = min(t0, t1), hi = max(t0, t1);
    float near = max(max(lo.x, lo.y), lo.z), far = min(min(hi.x, hi.y), hi.z);
    return near <= far && far > 0.0;
}

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= state.count) return;
    Patch p = src[i];
    for (int c = 0; c < 4; ++c) {
        vec3 x = p.x[c].xyz, v = p.v[c].xyz;
        advance(x, v);
        p.x[c].xyz = x;
        p.v[c].xyz = v;
    }
    vec3 mid = patch_mid(p);
    // Eq. 18 with the extinction volume (sigma_r = sigma_a + sigma_s, Eq. 5).
    vec3 sigma = extinction_at(mid);
    if (any(greaterThan(sigma, vec3(0.0)))) {
        p.flux.rgb *= exp(-sigma * DT / index_at(mid));
    }
    vec3 normal = patch_normal(p);
    vec3 dir = patch_dir(p);
    float area = length(normal);
    bool singular = !(dot(normal, dir) > 0.0);
    vec3 voxel = (LIGHT_MAX - LIGHT_MIN) / vec3(imageSize(irradiance));
    vec3 lo = min(min(p.x[0].xyz, p.x[1].xyz), min(p.x[2].xyz, p.x[3].xyz));
    vec3 hi = max(max(p.x[0].xyz, p.x[1].xyz), max(p.x[2].xyz, p.x[3].xyz));
    bool near_box = all(greaterThanEqual(hi, LIGHT_MIN - voxel)) && all(lessThanEqual(lo, LIGHT_MAX + voxel));
    uint cls = 1u;
    if (singular || max(p.flux.r, max(p.flux.g, p.flux.b)) < MIN_FLUX) {
        cls = 0u;
    } else if (!near_box && !heads_into_box(mid, dir)) {
        cls = 0u;   // left the simulation volume (and will not re-enter: straight in air)
    } else if (near_box && any(greaterThan(hi - lo, voxel))) {
        cls = 4u;   // tessellate; outside the box rays are straight and need no resolution
    }
    classes[i] = cls;
    src[i] = p;

    uvec2 deposit = uvec2(0xffffffffu, 0u);
    if (!singular && area > 0.0 && in_light_box(mid)) {
        vec3 e = p.flux.rgb / area;   // Eq. 17: dE_omega(t) = dE_omega(0) A(0) / A(t)
        float key = max(e.r, max(e.g, e.b));
        if (key > 0.0 && !isinf(key) && !isnan(key)) {
            ivec3 q = light_voxel(mid);
            ivec3 size = imageSize(irradiance);
            uint cell = uint(q.x + size.x * (q.y + size.y * q.z));
            deposit = uvec2(cell, floatBitsToUint(key));
            atomicMax(keys[cell], deposit.y);
        }
    }
    deposits[i] = deposit;
}
