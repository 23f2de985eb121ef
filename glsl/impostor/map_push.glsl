// Push constants of the impostor map passes (src/technique/impostor/distance_impostor.rs, MapPush).
#include "prism_shared.glsl"
layout(push_constant) uniform MapPushBlock { MapPush pc; };
