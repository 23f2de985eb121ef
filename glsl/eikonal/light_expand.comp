#version 450
// The HistoPyramid's output generator with data expansion (Ihrke et al. 2007, section
// 5.2.3: "instead of receiving four equal patch copies, we then introduce specific behavior
// in the output generator to tessellate the input into four smaller patches"). Output slot
// j holds (input patch, index among its outputs) from histopyramid_traverse.comp: a
// retained patch is copied; output k of a tessellated one is its k-th quarter of the
// bilinear split (section 4.2.3, Fig. 4 right), the new edge midpoints and centre moved
// back onto the curved wavefront, each with a quarter of the flux (conserved).
#include "light_common.glsl"
layout(local_size_x = LIGHT_GROUP) in;

// The point of the wavefront between particles (xa, va) and (xb, vb): the chord midpoint
// moved along the mean direction by the sagitta of the circular arc through both particles
// normal to their directions. The arc's radius is |xb - xa| / (2 sin(theta/2)), theta the
// angle between the directions, so the sagitta is |xb - xa| / 2 * tan(theta / 4); ahead of
// the chord for a diverging wavefront, behind it for a converging one.
void wavefront_midpoint(vec3 xa, vec3 va, vec3 xb, vec3 vb, out vec3 x, out vec3 v) {
    vec3 da = normalize(va), db = normalize(vb);
    vec3 d = da + db;
    d = dot(d, d) > 1e-12 ? normalize(d) : da;
    float theta = acos(clamp(dot(da, db), -1.0, 1.0));
    float sagitta = 0.5 * distance(xa, xb) * tan(0.25 * theta);
    float diverging = dot(db - da, xb - xa) >= 0.0 ? 1.0 : -1.0;
    x = 0.5 * (xa + xb) + diverging * sagitta * d;
    v = d * index_at(x);
}

// Output j: the next list's entry j, or past its `next` entries the spill list's entry
// after those that earlier steps spilled.
void emit(uint j, Patch q) {
    if (j < state.next) {
        dst[j] = q;
    } else {
        spill[state.spilled - state.spill_new + (j - state.next)] = q;
    }
}

// The initial particles among quarter k's corners (x[3].w, src/shader_structs.rs `Patch`):
// its corner k is the parent's corner k, the others are new.
float quarter_particles(float parent, uint k) {
    uint w = uint(parent), first = w / 8u, code = w % 8u;
    if (code == 4u) return float(first * 8u + k);
    if (code == k) return parent;
    return 5.0;
}

void main() {
    uint j = gl_GlobalInvocationID.x;
    if (j >= state.next + state.spill_new) return;
    uvec2 pair = pairs[j];
    Patch p = src_patch(pair.x);
    if (classes[pair.x] != 4u) {
        emit(j, p);
        return;
    }
    // Quarter k of the bilinear split (a 3x3 grid of points in halves of the parent's
    // parameter square) has the parent's corner k, the wavefront points halfway to its two
    // neighbouring corners, and the centre; in the parent's order its corner k is the
    // parent's. Only this output's quarter is computed: four of the split's six wavefront
    // midpoints (a CPU device computes every lane's, so one quarter per lane is what all
    // four would cost a group).
    uint k = min(pair.y, 3u);
    uint next = (k + 1u) & 3u, prev = (k + 3u) & 3u;
    vec3 xe0, ve0, xe1, ve1;
    wavefront_midpoint(p.x[k].xyz, p.v[k].xyz, p.x[next].xyz, p.v[next].xyz, xe0, ve0);
    wavefront_midpoint(p.x[k].xyz, p.v[k].xyz, p.x[prev].xyz, p.v[prev].xyz, xe1, ve1);
    vec3 xa, va, xb, vb;
    wavefront_midpoint(p.x[0].xyz, p.v[0].xyz, p.x[2].xyz, p.v[2].xyz, xa, va);
    wavefront_midpoint(p.x[1].xyz, p.v[1].xyz, p.x[3].xyz, p.v[3].xyz, xb, vb);
    vec3 xc = 0.5 * (xa + xb);
    vec3 vc = normalize(va + vb) * index_at(xc);
    // Output corner c is the ((c - k) & 3)-th of (corner k, towards next, centre, towards
    // prev), chosen by selects: a CPU device writes an array at a per-lane index lane by
    // lane. v.w by slot: the step count and the Fresnel run in progress (light_step.glsl),
    // which the quarters continue.
    Patch out_patch;
    vec3 xk = p.x[k].xyz, vk = p.v[k].xyz;
    for (uint c = 0u; c < 4u; ++c) {
        uint j = (c + 4u - k) & 3u;
        out_patch.x[c] = vec4(j == 0u ? xk : j == 1u ? xe0 : j == 2u ? xc : xe1, 0.0);
        out_patch.v[c] = vec4(j == 0u ? vk : j == 1u ? ve0 : j == 2u ? vc : ve1, p.v[c].w);
    }
    // Each quarter is the stream tube (Fig. 3) of a quarter of the parent's particles'
    // parameter square, which carried a quarter of its flux at birth (uniform irradiance
    // over a patch of at most a voxel): flux / 4. Splitting by the quarters' current areas
    // instead moved flux towards the stretched side of patches sheared across the ball's
    // rim (a dark band beside eikonal_sphere's shadow, and as much extra in its caustic).
    set_patch_flux(out_patch, patch_flux(p) * 0.25);
    out_patch.x[3].w = quarter_particles(p.x[3].w, k);
    emit(j, out_patch);
}
