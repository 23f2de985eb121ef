#version 450
#extension GL_EXT_shader_atomic_float : require
// light_resolve.glsl reading the accumulator as floats (R32_SFLOAT,
// light_step_float_atomics.comp).
#define ACCUM_FLOAT_ATOMICS
#include "light_resolve.glsl"
