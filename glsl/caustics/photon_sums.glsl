// The layout of the per-texel sums that glsl/caustics/photon_bin.comp fills and
// photon_scatter.glsl reads (render.photon_buffer.merge_texels): per rectangle k, layers
// SUM_LAYERS (k - 1) + ..., each channel's power as a 64-bit fixed-point number (low word at
// 2c, high word at 2c + 1), then the count, then 0 for no photon or else ~(the texel's first
// photon's index). GREY: every photon's power is the same in red, green and blue (grey lights,
// and specular materials that filter no colour: photon_buffer.rs `grey_photons`), so one sum
// stands for the three, at half the atomics.
#ifndef PRISM_PHOTON_SUMS_GLSL
#define PRISM_PHOTON_SUMS_GLSL
layout(constant_id = 0) const uint GREY = 0;
const int SUM_CHANNELS = GREY != 0u ? 1 : 3;
const int SUM_COUNT = 2 * SUM_CHANNELS;
const int SUM_OWNER = SUM_COUNT + 1;
const int SUM_LAYERS = SUM_OWNER + 1;
#endif
