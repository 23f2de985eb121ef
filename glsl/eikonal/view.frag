#version 450
// Eikonal view renderer (Ihrke et al. 2007, sections 4.1 and 5.3): the camera ray enters
// the volume's proxy box (ray-box intersection; section 5.1's "suitable proxy geometry to
// start the ray casting"), is marched through the smoothed index field with the ray
// equation dx/ds = v/n, dv/ds = grad n (Eqs. 9-10; Euler Eqs. 11-12 or classical RK4),
// loses radiance by Beer-Lambert absorption along the curved path (Eq. 5 with T = 1), and
// its exit direction looks up the environment (the background radiance L_bg of Eq. 1).
// No explicit ray-surface intersection: the bending comes from grad n alone.
#include "frame.glsl"
#include "environment.glsl"
layout(constant_id = 0) const uint INTEGRATOR = EIKONAL_EULER;
layout(constant_id = 1) const float STEP = 0.01;      // metres of arc length per step
layout(constant_id = 2) const uint MAX_STEPS = 1024u;
layout(constant_id = 3) const float BOX_MIN_X = -1.0;
layout(constant_id = 4) const float BOX_MIN_Y = -1.0;
layout(constant_id = 5) const float BOX_MIN_Z = -1.0;
layout(constant_id = 6) const float BOX_MAX_X = 1.0;
layout(constant_id = 7) const float BOX_MAX_Y = 1.0;
layout(constant_id = 8) const float BOX_MAX_Z = 1.0;
layout(constant_id = 9) const float SIGMA_R = 0.0;     // sigma_a per metre
layout(constant_id = 10) const float SIGMA_G = 0.0;
layout(constant_id = 11) const float SIGMA_B = 0.0;
layout(constant_id = 12) const float REGION_X = 0.0;   // absorbing sphere (radius 0: the whole box)
layout(constant_id = 13) const float REGION_Y = 0.0;
layout(constant_id = 14) const float REGION_Z = 0.0;
layout(constant_id = 15) const float REGION_RADIUS = 0.0;
// --- branch `light` (issue 7): single scattering from the light simulator (scatter.glsl).
layout(constant_id = 16) const uint SCATTER = 0u;           // 1: a light simulation ran
layout(constant_id = 17) const float SIGMA_S_R = 0.0;      // sigma_s per metre
layout(constant_id = 18) const float SIGMA_S_G = 0.0;
layout(constant_id = 19) const float SIGMA_S_B = 0.0;
layout(constant_id = 20) const float HG_G = 0.0;
layout(constant_id = 21) const float LIGHT_MIN_X = 0.0;    // the irradiance volume's box
layout(constant_id = 22) const float LIGHT_MIN_Y = 0.0;
layout(constant_id = 23) const float LIGHT_MIN_Z = 0.0;
layout(constant_id = 24) const float LIGHT_MAX_X = 1.0;
layout(constant_id = 25) const float LIGHT_MAX_Y = 1.0;
layout(constant_id = 26) const float LIGHT_MAX_Z = 1.0;
#include "scatter.glsl"
// --- end branch `light`
layout(set = 1, binding = BINDING_GBUF_DEPTH) uniform sampler2D gbuf_depth;
// xyz: grad n per metre, w: n - 1, at the voxel centres.
layout(set = 1, binding = BINDING_EIKONAL_FIELD) uniform sampler3D field;
layout(location = 0) in vec2 in_uv;
layout(location = 0) out vec4 out_radiance;

const vec3 BOX_MIN = vec3(BOX_MIN_X, BOX_MIN_Y, BOX_MIN_Z);
const vec3 BOX_MAX = vec3(BOX_MAX_X, BOX_MAX_Y, BOX_MAX_Z);

// One voxel; beyond the box the air has n = 1 and no gradient.
vec4 voxel(ivec3 q, ivec3 size) {
    return all(greaterThanEqual(q, ivec3(0))) && all(lessThan(q, size)) ? texelFetch(field, q, 0) : vec4(0.0);
}

// Trilinear interpolation in full precision (the same on every device), (grad n, n - 1).
vec4 sample_field(vec3 x) {
    ivec3 size = textureSize(field, 0);
    vec3 u = (x - BOX_MIN) / (BOX_MAX - BOX_MIN) * vec3(size) - 0.5;
    u = clamp(u, vec3(-1.0), vec3(size));
    vec3 f = fract(u);
    ivec3 i = ivec3(floor(u));
    vec4 c00 = mix(voxel(i, size), voxel(i + ivec3(1, 0, 0), size), f.x);
    vec4 c10 = mix(voxel(i + ivec3(0, 1, 0), size), voxel(i + ivec3(1, 1, 0), size), f.x);
    vec4 c01 = mix(voxel(i + ivec3(0, 0, 1), size), voxel(i + ivec3(1, 0, 1), size), f.x);
    vec4 c11 = mix(voxel(i + ivec3(0, 1, 1), size), voxel(i + ivec3(1, 1, 1), size), f.x);
    return mix(mix(c00, c10, f.y), mix(c01, c11, f.y), f.z);
}

// The right-hand side of Eqs. 9-10 at (x, v): (dx/ds, dv/ds) = (v / n, grad n).
void rhs(vec3 x, vec3 v, out vec3 dx, out vec3 dv) {
    vec4 s = sample_field(x);
    dx = v / max(1.0 + s.w, 1e-3);
    dv = s.xyz;
}

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

void main() {
    vec3 o = frame.camera_position.xyz;
    vec3 d = camera_ray(in_uv);
    vec2 t = ray_box(o, d);
    if (t.x > t.y || t.y < 0.0) discard;
    float t_enter = max(t.x, 0.0);
    // Geometry in front of the volume hides it.
    float depth = texelFetch(gbuf_depth, ivec2(gl_FragCoord.xy), 0).r;
    if (depth > 0.0 && distance(world_from_depth(in_uv, depth), o) < t_enter) discard;

    vec3 x = o + d * t_enter;
    vec3 v = d * (1.0 + sample_field(x).w);  // |v| = n: v is the ray's optical direction
    vec3 sigma = vec3(SIGMA_R, SIGMA_G, SIGMA_B);
    bool absorbs = any(greaterThan(sigma, vec3(0.0)));
    vec3 optical_depth = vec3(0.0);
    // --- branch `light`: in-scattered radiance, and whether the ray met the medium at all
    // (a ray through the box's air only keeps what deferred shading drew, e.g. the floor).
    vec3 scattered = vec3(0.0);
    vec3 sigma_s = vec3(SIGMA_S_R, SIGMA_S_G, SIGMA_S_B);
    bool touched = false;
    // Rays that leave the box stop one step past its face at most.
    float margin = STEP;
    for (uint i = 0u; i < MAX_STEPS && in_box(x, margin); ++i) {
        vec3 x0 = x;
        float h = STEP;
        if (INTEGRATOR == EIKONAL_RK4) {
            vec3 k1x, k1v, k2x, k2v, k3x, k3v, k4x, k4v;
            rhs(x, v, k1x, k1v);
            rhs(x + 0.5 * h * k1x, v + 0.5 * h * k1v, k2x, k2v);
            rhs(x + 0.5 * h * k2x, v + 0.5 * h * k2v, k3x, k3v);
            rhs(x + h * k3x, v + h * k3v, k4x, k4v);
            x += h / 6.0 * (k1x + 2.0 * k2x + 2.0 * k3x + k4x);
            v += h / 6.0 * (k1v + 2.0 * k2v + 2.0 * k3v + k4v);
        } else {
            // Eqs. 11-12.
            vec3 dx, dv;
            rhs(x, v, dx, dv);
            x += h * dx;
            v += h * dv;
        }
        if (absorbs) {
            // Eq. 5: sigma integrated along the curved path, midpoint rule per segment.
            vec3 mid = 0.5 * (x0 + x);
            bool inside = REGION_RADIUS <= 0.0 || distance(mid, vec3(REGION_X, REGION_Y, REGION_Z)) <= REGION_RADIUS;
            if (inside && in_box(mid, 0.0)) {
                // --- branch `light`: Eq. 1's integral of T sigma_s p dE before this
                // segment's extinction (sigma includes sigma_s, Eq. 5: sigma_r).
                if (SCATTER != 0u && any(greaterThan(sigma_s, vec3(0.0)))) {
                    vec3 light_min = vec3(LIGHT_MIN_X, LIGHT_MIN_Y, LIGHT_MIN_Z);
                    vec3 light_max = vec3(LIGHT_MAX_X, LIGHT_MAX_Y, LIGHT_MAX_Z);
                    vec3 to_eye = -normalize(x - x0);
                    scattered += exp(-optical_depth) * sigma_s * distance(x0, x) *
                                 inscatter(mid, to_eye, light_min, light_max, HG_G);
                }
                optical_depth += sigma * distance(x0, x);
            }
        }
        touched = touched || abs(sample_field(x).w) > 1e-4;
    }
    // --- branch `light`: the ray crossed only air and no scattering medium: keep what is
    // behind it in the G-buffer (deferred shading's floor) instead of the environment.
    if (!touched && !(optical_depth.r + optical_depth.g + optical_depth.b > 0.0)) discard;
    // A degenerate momentum (never for n > 0) keeps the incoming direction.
    vec3 exit_dir = dot(v, v) > 1e-20 ? normalize(v) : d;
    vec3 L = exp(-optical_depth) * environment(exit_dir) + scattered;
    out_radiance = vec4(finite_or_zero(L), 1.0);
}
