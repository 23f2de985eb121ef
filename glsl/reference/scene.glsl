// The scene as the reference's compute passes see it: set 0 holds the tracer's buffers
// (trace.glsl) beside the materials and the environment.
#ifndef PRISM_REFERENCE_SCENE_GLSL
#define PRISM_REFERENCE_SCENE_GLSL
#include "common.glsl"

layout(local_size_x = REF_WORKGROUP) in;

// The 1-D index of this invocation. The kernels are dispatched in rows of at most
// maxComputeWorkGroupCount[0] groups (dispatch_size in src/reference/mod.rs), so that images
// and photon passes larger than 64 times that limit are covered in full.
uint invocation_index() {
    return gl_GlobalInvocationID.y * (gl_NumWorkGroups.x * gl_WorkGroupSize.x) + gl_GlobalInvocationID.x;
}

layout(push_constant) uniform RefPushBlock { RefPush push; };

layout(set = 0, binding = REF_BINDING_MATERIALS, std430) readonly buffer Materials { GpuMaterial materials[]; };
layout(set = 0, binding = REF_BINDING_ENVIRONMENT) uniform sampler2D environment_map;

vec3 environment(vec3 d) { return environment_lookup(environment_map, d); }

#include "trace.glsl"
#endif
