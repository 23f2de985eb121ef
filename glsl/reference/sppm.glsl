// Buffers of stochastic progressive photon mapping (Hachisuka & Jensen 2009), used for the
// reference's caustics: per-pixel statistics and visible points, the photons of the current
// iteration, and a hashed grid of linked lists over them.
#ifndef PRISM_REFERENCE_SPPM_GLSL
#define PRISM_REFERENCE_SPPM_GLSL
#include "scene.glsl"


struct Photon {
    vec4 pos;        // w: next photon in the same grid bucket (uint bits; 0xffffffff ends)
    vec4 flux;       // rgb, W
    vec4 dir;        // incoming direction
};

const uint END_OF_LIST = 0xffffffffu;

layout(set = 0, binding = REF_BINDING_ACCUM, std430) buffer Accum { vec4 accum[]; };   // sum of L, sample count
layout(set = 0, binding = REF_BINDING_PIXELS, std430) buffer Pixels { PixelState pixels[]; };
layout(set = 0, binding = REF_BINDING_PHOTONS, std430) buffer Photons { Photon photons[]; };
layout(set = 0, binding = REF_BINDING_GRID, std430) buffer Grid { uint heads[]; };
layout(set = 0, binding = REF_BINDING_COUNTERS, std430) buffer Counters { uint photon_count; };
layout(set = 0, binding = REF_BINDING_DEBUG, std430) buffer Debug { vec4 debug_data[]; };

uint grid_bucket(ivec3 c) {
    uint h = (uint(c.x) * 73856093u) ^ (uint(c.y) * 19349663u) ^ (uint(c.z) * 83492791u);
    return h % ref.photon.z;
}
ivec3 grid_cell(vec3 p) { return ivec3(floor(p / ref.grid.x)); }
#endif
