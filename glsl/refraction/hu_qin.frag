#version 450
// Hu & Qin 2007's refraction (render.refraction = "hu_qin"): hu_qin.glsl.
#include "hu_qin.glsl"
