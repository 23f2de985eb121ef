#version 450
// Reference photon tracing for caustics: light that reaches a diffuse surface after at least
// one specular interaction. Photons are aimed only at the bounding spheres of specular
// objects (light that reaches a diffuse surface directly is the camera paths' exact direct
// lighting); each carries flux = emitted power / (photons * pdf), with the pdf summed over
// every target whose cone (point light) or disk (directional light) contains the sample, so
// overlapping targets are not counted twice.
#define REF_STAT_STEP_CAP_SLOT REF_STAT_STEP_CAP_PHOTONS
#include "sppm.glsl"
#include "volume.glsl"

// Uniform direction in the cone around unit axis a with cos(half-angle) cos_max.
vec3 sample_cone(vec3 a, float cos_max, inout uint rng) {
    float cos_t = mix(1.0, cos_max, rand(rng));
    float sin_t = sqrt(max(0.0, 1.0 - cos_t * cos_t));
    float phi = 2.0 * PI * rand(rng);
    vec3 t, b;
    basis(a, t, b);
    return normalize(sin_t * cos(phi) * t + sin_t * sin(phi) * b + cos_t * a);
}

// Solid angle of target k seen from x (4 pi from inside it), and whether d lies in its cone.
float cone(vec3 x, vec4 target, vec3 d, out bool inside) {
    vec3 to = target.xyz - x;
    float dist = length(to);
    if (dist <= target.w) {
        inside = true;
        return 4.0 * PI;
    }
    float sin_max = target.w / dist;
    float cos_max = sqrt(max(0.0, 1.0 - sin_max * sin_max));
    inside = dot(d, to / dist) >= cos_max;
    return 2.0 * PI * (1.0 - cos_max);
}

// Photon idx of the pass's `total`.
void trace_photon(uint idx, uint total) {
    uint lights = ref.dims.z, targets = ref.counts.z;
    // Debug records (tests): (flux, outcome) at idx, where it was deposited at total + idx.
    debug_data[idx] = vec4(0.0, 0.0, 0.0, float(PHOTON_MISSED));
    debug_data[total + idx] = vec4(0.0);
    if (lights == 0u || targets == 0u) return;
    uint rng = rng_init(idx, push.iteration, push.seed ^ 0x68bc21ebu);

    // Photons are shared evenly between the lights: index idx belongs to light idx % lights.
    uint li = idx % lights;
    float n_light = float((total - li + lights - 1u) / lights);
    RefLight light = ref.lights[li];
    vec4 target = ref.targets[min(uint(rand(rng) * float(targets)), targets - 1u)];
    vec3 o, d, flux;
    if (uint(light.position.w + 0.5) == LIGHT_POINT) {
        o = light.position.xyz;
        vec3 to = target.xyz - o;
        float dist = length(to);
        if (dist <= target.w) {
            float z = 1.0 - 2.0 * rand(rng), phi = 2.0 * PI * rand(rng), r = sqrt(max(0.0, 1.0 - z * z));
            d = vec3(r * cos(phi), r * sin(phi), z);
        } else {
            float sin_max = target.w / dist;
            d = sample_cone(to / dist, sqrt(max(0.0, 1.0 - sin_max * sin_max)), rng);
        }
        float pdf = 0.0;
        for (uint k = 0u; k < targets; ++k) {
            bool inside;
            float omega = cone(o, ref.targets[k], d, inside);
            if (inside) pdf += 1.0 / omega;
        }
        flux = light.intensity.rgb / (n_light * pdf / float(targets));
    } else {
        d = light.position.xyz;
        vec3 t, b;
        basis(d, t, b);
        float r = target.w * sqrt(rand(rng)), phi = 2.0 * PI * rand(rng);
        vec3 q = target.xyz + r * (cos(phi) * t + sin(phi) * b);
        float pdf = 0.0;
        for (uint k = 0u; k < targets; ++k) {
            vec3 rel = q - ref.targets[k].xyz;
            vec3 perp = rel - dot(rel, d) * d;
            if (dot(perp, perp) <= ref.targets[k].w * ref.targets[k].w) pdf += 1.0 / (PI * ref.targets[k].w * ref.targets[k].w);
        }
        flux = light.intensity.rgb / (n_light * pdf / float(targets));
        // Start outside everything: the scene's bounding sphere has radius proj.w.
        o = q - d * (4.0 * ref.proj.w + abs(dot(q, d)));
    }
    int channel = -1;
    if ((ref.photon.w & REF_FLAG_DISPERSION) != 0u) {
        channel = min(int(rand(rng) * 3.0), 2);
        vec3 f = vec3(0.0);
        f[channel] = 3.0 * flux[channel];
        flux = f;
    }
    flux = finite_or_zero(flux);

    uint outcome = PHOTON_LOST;
    vec3 deposit = vec3(0.0);
    for (uint bounce = 0u; bounce <= ref.counts.w; ++bounce) {
        Hit h = trace(o, d, 3.4e38);
        // A refractive volume before the surface: the photon crosses it along the curved
        // path (RK4, Fresnel at its boundary, absorption), as camera paths do; the crossing
        // counts as a specular interaction, so the light behind it is deposited as caustic.
        float tv;
        if (region_entry(o, d, h.kind == 0u ? 3.4e38 : h.t, tv)) {
            vec3 unused = vec3(0.0);
            if (!volume_cross(o, d, tv, flux, unused, channel, rng)) break;
            continue;
        }
        if (h.kind == 0u) {
            outcome = bounce == 0u ? PHOTON_MISSED : PHOTON_ESCAPED;
            break;
        }
        Surface s = surface_at(o, d, h);
        if (kind_of(materials[s.material]) == MATERIAL_DIFFUSE) {
            if (bounce == 0u) {
                outcome = PHOTON_DIRECT;   // direct light: the camera paths' shadow rays own it
                break;
            }
            outcome = PHOTON_DEPOSITED;
            deposit = s.p;
            uint slot = atomicAdd(photon_count, 1u);
            if (slot < ref.photon.y) {
                uint next = atomicExchange(heads[grid_bucket(grid_cell(s.p))], slot);
                photons[slot].pos = vec4(s.p, uintBitsToFloat(next));
                photons[slot].flux = vec4(flux, 0.0);
                photons[slot].dir = vec4(d, 0.0);
            }
            break;
        }
        if (!specular_step(s, o, d, flux, h.t, channel, rand(rng), false)) break;
    }
    debug_data[idx] = vec4(flux, float(outcome));
    debug_data[total + idx] = vec4(deposit, 0.0);
}

void main() {
    uint idx = invocation_index();
    uint total = ref.photon.x;
    if (idx >= total) return;
    trace_photon(idx, total);
    // After the whole photon path, whatever returns it takes (sppm.glsl).
    loop_canary(REF_STAT_CUT_PHOTONS);
}
