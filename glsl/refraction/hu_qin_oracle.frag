#version 450
// Hu & Qin 2007 with the oracle of render.hu_qin.oracle: hu_qin.glsl with the exact tracer bound
// in set 2, an analysis tool (prism ablation).
#define ORACLE_TRACE
#include "hu_qin.glsl"
