#version 450
// Caustics mapping with the oracle of render.caustics_map.oracle = "receiver": splat_hits.glsl
// with the exact tracer bound in set 1 and the receiver estimate of §III.C (Eq. 1-2) replaced
// by the exact hit, an analysis tool (prism ablation).
#define ORACLE_TRACE
#include "splat_hits.glsl"
