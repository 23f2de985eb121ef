#version 450
// light_resolve.glsl reading the accumulator as bits (R32_UINT, light_step.comp).
#include "light_resolve.glsl"
