#version 450
// Double refraction with the oracle of render.impostor.oracle = "hit": refract.glsl with the
// exact tracer bound in set 2, an analysis tool (prism ablation).
#define ORACLE_TRACE
#include "refract.glsl"
