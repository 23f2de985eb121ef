#version 450
#include "reflect.glsl"
