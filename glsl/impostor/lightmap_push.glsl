// Push constants of the caustic-map pass of light-map caustics
// (src/technique/impostor/impostor_lightmap.rs, CausticPush).
#include "prism_shared.glsl"
layout(push_constant) uniform CausticPushBlock { CausticPush pc; };
