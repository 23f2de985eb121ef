// The photons of one photon pass in a hashed grid of linked lists, and the density estimate
// over them: written by the reference's photon kernel (photons.comp), searched by its SPPM
// gather (gather.comp) and by the raytrace technique at the diffuse vertices its branches
// reach (glsl/raytrace/raytrace.frag). The buffers lie in set REF_SET with the tracer's
// (trace.glsl); an includer that only reads them defines PHOTON_GRID_ACCESS as readonly.
#ifndef PRISM_REFERENCE_PHOTON_GRID_GLSL
#define PRISM_REFERENCE_PHOTON_GRID_GLSL
#include "trace.glsl"
#ifndef PHOTON_GRID_ACCESS
#define PHOTON_GRID_ACCESS
#endif

struct Photon {
    vec4 pos;        // w: next photon in the same grid bucket (uint bits; 0xffffffff ends)
    vec4 flux;       // rgb, W
    vec4 dir;        // incoming direction
};

const uint END_OF_LIST = 0xffffffffu;

layout(set = REF_SET, binding = REF_BINDING_PHOTONS, std430) PHOTON_GRID_ACCESS buffer Photons { Photon photons[]; };
layout(set = REF_SET, binding = REF_BINDING_GRID, std430) PHOTON_GRID_ACCESS buffer Grid { uint heads[]; };

// ref.photon.z buckets; cells of ref.grid.x.
uint grid_bucket(ivec3 c) {
    uint h = (uint(c.x) * 73856093u) ^ (uint(c.y) * 19349663u) ^ (uint(c.z) * 83492791u);
    return h % ref.photon.z;
}
ivec3 grid_cell(vec3 p) { return ivec3(floor(p / ref.grid.x)); }

// The photons within distance R of p that arrived on the side n faces (the side the camera
// sees): their number M and their summed flux phi.
//
// The cell size is twice the largest radius (ref.grid.x = 2.002 ref.grid.y) and R never
// exceeds it, so the ball of radius R overlaps at most 2 cells per axis: its photons lie in
// at most 2x2x2 cells. (With cells of size R the ball can span 3 per axis, and photons beyond
// the 8 buckets visited were lost, dimming caustics by an amount that depended on where the
// point fell on the grid.) Buckets visited twice (hash collisions) are skipped so that no
// photon is counted twice: each photon of the pass is visited at most once, which bounds the
// loop iterations of an invocation by the photons of a pass (MAX_PHOTONS_PER_PASS in
// src/reference/mod.rs says why that bound matters).
void photons_within(vec3 p, vec3 n, float R, out float M, out vec3 phi) {
    M = 0.0;
    phi = vec3(0.0);
    ivec3 lo = grid_cell(p - vec3(R)), hi = grid_cell(p + vec3(R));
    uint visited[8];   // 2x2x2 cells at most (see above)
    uint n_visited = 0u;
    for (int z = lo.z; z <= hi.z; ++z)
    for (int y = lo.y; y <= hi.y; ++y)
    for (int x = lo.x; x <= hi.x; ++x) {
        uint bucket = grid_bucket(ivec3(x, y, z));
        bool seen = false;
        for (uint k = 0u; k < n_visited; ++k) seen = seen || visited[k] == bucket;
        if (seen || n_visited >= 8u) continue;   // never taken: the cells are slightly larger than 2 R
        visited[n_visited++] = bucket;
        uint i = heads[bucket];
        for (uint guard = 0u; i != END_OF_LIST && guard < ref.photon.y; ++guard) {
            Photon ph = photons[i];
            vec3 q = ph.pos.xyz - p;
            if (dot(q, q) <= R * R && dot(ph.dir.xyz, n) < 0.0) {
                M += 1.0;
                phi += ph.flux.rgb;
            }
            i = floatBitsToUint(ph.pos.w);
        }
    }
}
#endif
