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

void main() {
    uint j = gl_GlobalInvocationID.x;
    if (j >= state.next + state.spill_new) return;
    uvec2 pair = pairs[j];
    Patch p = src[pair.x];
    if (classes[pair.x] != 4u) {
        emit(j, p);
        return;
    }
    // The 3x3 grid of points of the split, (a, b) in halves: corners 0..3 are (0,0), (2,0),
    // (2,2), (0,2).
    // gw: the particles' numbers (x.w), -1 for the ones created here.
    vec3 gx[9], gv[9];
    float gw[9] = float[9](p.x[0].w, -1.0, p.x[1].w, -1.0, -1.0, -1.0, p.x[3].w, -1.0, p.x[2].w);
    gx[0] = p.x[0].xyz; gv[0] = p.v[0].xyz;
    gx[2] = p.x[1].xyz; gv[2] = p.v[1].xyz;
    gx[8] = p.x[2].xyz; gv[8] = p.v[2].xyz;
    gx[6] = p.x[3].xyz; gv[6] = p.v[3].xyz;
    wavefront_midpoint(gx[0], gv[0], gx[2], gv[2], gx[1], gv[1]);
    wavefront_midpoint(gx[2], gv[2], gx[8], gv[8], gx[5], gv[5]);
    wavefront_midpoint(gx[6], gv[6], gx[8], gv[8], gx[7], gv[7]);
    wavefront_midpoint(gx[0], gv[0], gx[6], gv[6], gx[3], gv[3]);
    vec3 xa, va, xb, vb;
    wavefront_midpoint(gx[0], gv[0], gx[8], gv[8], xa, va);
    wavefront_midpoint(gx[2], gv[2], gx[6], gv[6], xb, vb);
    gx[4] = 0.5 * (xa + xb);
    gv[4] = normalize(va + vb) * index_at(gx[4]);
    // Quarter k's corners in the parent's order: lower-left grid index and its 3 others.
    const int base[4] = int[4](0, 1, 4, 3);
    Patch q[4];
    for (int k = 0; k < 4; ++k) {
        int b = base[k];
        int idx[4] = int[4](b, b + 1, b + 4, b + 3);
        for (int c = 0; c < 4; ++c) {
            q[k].x[c] = vec4(gx[idx[c]], gw[idx[c]]);
            // w: the Fresnel run in progress (light_step.glsl), by slot: the quarters continue it.
            q[k].v[c] = vec4(gv[idx[c]], p.v[c].w);
        }
    }
    uint k = min(pair.y, 3u);
    Patch out_patch = q[k];
    // Each quarter is the stream tube (Fig. 3) of a quarter of the parent's particles'
    // parameter square, which carried a quarter of its flux at birth (uniform irradiance
    // over a patch of at most a voxel): flux / 4. Splitting by the quarters' current areas
    // instead moved flux towards the stretched side of patches sheared across the ball's
    // rim (a dark band beside eikonal_sphere's shadow, and as much extra in its caustic).
    // w: the parent's step count (light_step.glsl), which the quarters continue from.
    out_patch.flux = vec4(p.flux.rgb * 0.25, p.flux.w);
    emit(j, out_patch);
}
