// Push constants of the impostor-texture pass (src/technique/refraction/nearby_impostors.rs, NearbyImpostorPush).
#include "prism_shared.glsl"
layout(push_constant) uniform NearbyImpostorPushBlock { NearbyImpostorPush pc; };
