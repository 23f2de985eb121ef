#version 450
#extension GL_EXT_shader_atomic_float : require
// The light simulator's step kernel (light_step.glsl) with the deposits added by float
// atomics (VK_EXT_shader_atomic_float, shaderImageFloat32AtomicAdd), where the device has them.
#define ACCUM_FLOAT_ATOMICS
#include "light_step.glsl"
