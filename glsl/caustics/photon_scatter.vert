#version 450
// One point per photon (photon_scatter.glsl).
#include "photon_scatter.glsl"
