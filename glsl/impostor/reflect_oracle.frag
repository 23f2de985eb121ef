#version 450
// Localized reflections with the oracle of render.impostor.oracle = "hit": reflect.glsl with the
// exact tracer bound in set 2, an analysis tool (prism ablation).
#define ORACLE_TRACE
#include "reflect.glsl"
