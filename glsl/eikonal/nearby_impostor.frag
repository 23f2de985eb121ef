#version 450
// TE_i of the impostor rectangles around an eikonal volume (Hu & Qin 2007
// §2.2, src/technique/eikonal/eikonal_nearby.rs) when a light simulation ran: glsl/nearby/impostor.frag's
// level 0 with the diffuse radiance of glsl/eikonal/receiver.glsl, so that the floor seen
// through the volume carries the simulated caustic and shadow (Ihrke et al. 2007 §5.2).
#include "frame.glsl"
#include "lighting.glsl"
// The irradiance volume's box (src/technique/eikonal/eikonal_light.rs light_grid): constants 6..11, after
// impostor_body.glsl's 0..5; the light volumes in set 2 (set 1 is the impostors').
#define EIKONAL_LIGHT_SET 2
layout(constant_id = 6) const float LIGHT_MIN_X = 0.0;
layout(constant_id = 7) const float LIGHT_MIN_Y = 0.0;
layout(constant_id = 8) const float LIGHT_MIN_Z = 0.0;
layout(constant_id = 9) const float LIGHT_MAX_X = 1.0;
layout(constant_id = 10) const float LIGHT_MAX_Y = 1.0;
layout(constant_id = 11) const float LIGHT_MAX_Z = 1.0;
#include "scatter.glsl"
#include "receiver.glsl"
#define NEARBY_RECURSIVE 0
#define NEARBY_EIKONAL_LIGHT 1
#include "../nearby/impostor_body.glsl"
