#version 450
// Wyman 2005 with the oracle of render.wyman.oracle: wyman.glsl with the exact tracer bound in
// set 2, an analysis tool (prism ablation).
#define ORACLE_TRACE
#include "wyman.glsl"
