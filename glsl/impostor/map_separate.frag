#version 450
// Distance impostor with the distance in a separate texture (Szirmay-Kalos et al. 2005, §6).
#define IMPOSTOR_SEPARATE 1
#include "map_radiance.glsl"
