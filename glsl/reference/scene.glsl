// The scene as the reference's compute passes see it: set 0 holds the tracer's buffers
// (trace.glsl) beside the materials and the environment.
#ifndef PRISM_REFERENCE_SCENE_GLSL
#define PRISM_REFERENCE_SCENE_GLSL
#include "common.glsl"

layout(local_size_x = REF_WORKGROUP) in;

layout(push_constant) uniform RefPushBlock { RefPush push; };

layout(set = 0, binding = REF_BINDING_MATERIALS, std430) readonly buffer Materials { GpuMaterial materials[]; };
layout(set = 0, binding = REF_BINDING_ENVIRONMENT) uniform sampler2D environment_map;

vec3 environment(vec3 d) { return environment_lookup(environment_map, d); }

#include "trace.glsl"
#endif
