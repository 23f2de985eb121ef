#version 450
// One point per texel that photons reached, their sum (photon_scatter.glsl, photon_bin.comp):
// needs vertexPipelineStoresAndAtomics for the sums' reset.
#define MERGED
#include "photon_scatter.glsl"
