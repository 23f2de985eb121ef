#version 450
// The light simulator's step kernel (light_step.glsl) with the deposits added by a
// compare-and-swap loop on the accumulator's bits: core Vulkan, every device.
#include "light_step.glsl"
