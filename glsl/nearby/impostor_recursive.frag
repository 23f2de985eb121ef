#version 450
// Recursion level >= 1 of the impostor textures (Hu & Qin 2007 §2.2.1, Fig. 24g): mirrors and
// conductors reflect the impostors of the level below.
#define NEARBY_RECURSIVE 1
#include "impostor_body.glsl"
