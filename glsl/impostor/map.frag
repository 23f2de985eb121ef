#version 450
// Distance impostor with the distance in the alpha channel (Szirmay-Kalos et al. 2005, §2).
#define IMPOSTOR_SEPARATE 0
#include "map_radiance.glsl"
