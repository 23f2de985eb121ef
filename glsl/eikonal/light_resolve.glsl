// After every run of the light simulator (all lights, channels and tiles): the additive
// accumulator of light_step.glsl's track-length estimate becomes the irradiance and
// direction volumes that single scattering (scatter.glsl, Eq. 6) and the receivers
// (light_receiver.frag, Eq. 7) sample. One invocation per voxel (workgroups of 4^3: a 1D
// dispatch of a 256^3 volume's 3 * 10^7 voxels would pass maxComputeWorkGroupCount).
//
// With `render.eikonal.skip_air` the initial patches whose straight beams only cross air were
// not simulated (src/technique/eikonal/eikonal_light.rs `air_patches`). In air a beam stays
// straight and keeps its flux, so what they would have deposited is the intensity law in
// closed form, E = I / r^2 (point light) or E (directional), travelling along the beam: it
// is added here for every voxel whose light comes through a skipped patch. The step kernel
// deposits each segment with a trilinear tent two voxels wide, so a voxel near the edge
// between skipped and simulated patches received part of its light from each: the closed
// form is weighted by the tent's mean of the skip flags over the voxel's footprint, which is
// what the skipped patches' deposits would have summed to. Only where the volumes are read
// (READ_MASK, light_common.glsl), as the step kernel's deposits.
//
// With HIGHEST_ENERGY (the paper's voxelization, light_step.glsl) the slabs hold one ray per
// voxel, and a skipped beam's ray, dE = the closed form, takes the voxel where the voxel's
// centre lies in a skipped patch's beam (the paper's midpoint sample) and its energy is the
// higher: the same criterion.
#include "light_common.glsl"
layout(local_size_x = EIKONAL_GROUP, local_size_y = EIKONAL_GROUP, local_size_z = EIKONAL_GROUP) in;

layout(std430, set = 1, binding = LIGHT_BINDING_AIR_FACES) readonly buffer AirFaces { AirFace air_faces[]; };
// Per face, k x k flags in the initial wavefront's order (row j, then i): air_flags.
layout(std430, set = 1, binding = LIGHT_BINDING_AIR_SKIP) readonly buffer AirSkip { uint air_skip[]; };

// The flags (air_flags) of the cell of face f whose straight rays pass x: bit 0 skipped, bit 1
// near a cell of the other kind; 0 outside the face.
uint flags_at(AirFace f, vec3 x) {
    vec3 r = x - f.origin.xyz;
    vec2 uv = vec2(dot(r, f.t1.xyz), dot(r, f.t2.xyz));
    if (f.origin.w == 0.0) {
        float z = dot(r, f.axis.xyz);
        if (!(z > 0.0)) return 0u;
        uv /= z;
    }
    int k = int(f.t1.w);
    ivec2 cell = ivec2(floor((uv + f.axis.w) * (float(k) / (2.0 * f.axis.w))));
    if (any(lessThan(cell, ivec2(0))) || any(greaterThanEqual(cell, ivec2(k)))) return 0u;
    return air_skip[uint(f.t2.w) + uint(cell.y * k + cell.x)];
}

// The tent-weighted mean of the skip flag over x +- one voxel: the cell's own flag where no
// cell of the other kind is within the footprint's reach or where the footprint's corners
// all share the centre's flag (cells are rectangles in (u, v) and the footprint spans about
// one), else by a midpoint rule of 4 points per axis (the tent's mass 1/8, 3/8, 3/8, 1/8 at
// -3/4, -1/4, 1/4, 3/4 voxel).
float skipped_share(AirFace f, vec3 x, vec3 voxel) {
    uint centre = flags_at(f, x);
    if ((centre & 2u) == 0u) return float(centre & 1u);
    bool uniform_flags = true;
    for (int c = 0; c < 8 && uniform_flags; ++c) {
        vec3 o = vec3(c & 1, (c >> 1) & 1, (c >> 2) & 1) * 2.0 - 1.0;
        uniform_flags = (flags_at(f, x + o * voxel) & 1u) == (centre & 1u);
    }
    if (uniform_flags) return float(centre & 1u);
    const float at[4] = float[4](-0.75, -0.25, 0.25, 0.75);
    const float w[4] = float[4](0.125, 0.375, 0.375, 0.125);
    float share = 0.0;
    for (int k = 0; k < 4; ++k) {
        for (int j = 0; j < 4; ++j) {
            for (int i = 0; i < 4; ++i) {
                share += w[i] * w[j] * w[k] * float(flags_at(f, x + vec3(at[i], at[j], at[k]) * voxel) & 1u);
            }
        }
    }
    return share;
}

float slab_value(ivec3 q, int comp) {
    float v = accum_value(q, comp);
    return isnan(v) || isinf(v) ? 0.0 : v;
}

void main() {
    ivec3 size = imageSize(irradiance);
    ivec3 q = ivec3(gl_GlobalInvocationID);
    if (any(greaterThanEqual(q, size))) return;
    // A voxel that nothing reads (READ_MASK) keeps the zero the volumes were cleared to.
    if (!marked_read(q, size)) return;
    // Rounding of a take-back (run.sign = -1) can leave tiny negative sums: clamp.
    vec3 e = max(GRAY != 0u ? vec3(slab_value(q, 0)) : vec3(slab_value(q, 0), slab_value(q, 1), slab_value(q, 2)), vec3(0.0));
    vec3 d = vec3(slab_value(q, 3), slab_value(q, 4), slab_value(q, 5));
    float weight = DIRECTION_NEAREST != 0u ? max(slab_value(q, 6), 0.0) : 0.0;
    // One ray: its unit direction weighted like the sums' (E_r + E_g + E_b).
    if (HIGHEST_ENERGY != 0u) d *= e.r + e.g + e.b;
    vec3 voxel = (LIGHT_MAX - LIGHT_MIN) / vec3(size);
    vec3 x = LIGHT_MIN + (vec3(q) + 0.5) * voxel;
    for (uint i = 0u; i < AIR_FACES; ++i) {
        AirFace f = air_faces[i];
        float share = HIGHEST_ENERGY != 0u ? float(flags_at(f, x) & 1u) : skipped_share(f, x, voxel);
        if (share == 0.0) continue;
        bool point = f.origin.w == 0.0;
        vec3 r = x - f.origin.xyz;
        // Not nearer than the patches start (a light inside the box starts them at r0).
        vec3 light = point ? f.power.rgb / max(dot(r, r), f.power.w * f.power.w) : f.power.rgb;
        vec3 l = point ? normalize(r) : f.axis.xyz;
        float energy = light.r + light.g + light.b;
        if (HIGHEST_ENERGY != 0u) {
            if (energy > e.r + e.g + e.b) {
                e = light;
                d = l * energy;
            }
            continue;
        }
        e += share * light;
        d += share * l * energy;
        weight += share * energy;
    }
    float s = e.r + e.g + e.b;
    if (DIRECTION_NEAREST == 0u) weight = s;
    imageStore(irradiance, q, vec4(e, s > 0.0 ? 1.0 : 0.0));
    imageStore(direction, q, weight > 0.0 ? vec4(d, weight) : vec4(0.0));
}
