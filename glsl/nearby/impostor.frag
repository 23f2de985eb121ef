#version 450
// Recursion level 0 of the impostor textures (Hu & Qin 2007 §2.2.1): mirrors and conductors
// reflect the environment only.
#define NEARBY_RECURSIVE 0
#include "impostor_body.glsl"
