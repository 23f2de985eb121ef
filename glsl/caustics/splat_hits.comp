#version 450
// Caustics mapping's per-vertex light paths and receiver hits (Shah et al. 2007, §III.C-F):
// splat_hits.glsl.
#include "splat_hits.glsl"
