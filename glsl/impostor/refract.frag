#version 450
#include "refract.glsl"
