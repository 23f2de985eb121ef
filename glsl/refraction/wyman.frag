#version 450
// Wyman 2005's two-interface refraction (render.refraction = "wyman"): wyman.glsl.
#include "wyman.glsl"
