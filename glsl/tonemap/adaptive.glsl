// The adaptive tone map (Ihrke et al. 2007 §5.3: "an adaptive tone-mapping based on
// [Krawczyk et al. 2005] is applied prior to display"), shared by its two reduction kernels
// and its fragment shader. src/app/output.rs (`tonemap_adaptive`) is the same operator on
// the CPU, term for term; tests/tonemap.rs holds the two to 1/255.
#ifndef PRISM_TONEMAP_ADAPTIVE_GLSL
#define PRISM_TONEMAP_ADAPTIVE_GLSL
#include "prism_shared.glsl"


// Radiance beyond this is read as this, so that no luminance sum or product can overflow
// a float (the brightest real scene luminance, the sun's disc, is about 1.6e9 cd/m^2).
const float TONEMAP_MAX_RADIANCE = 1e30;
const float TONEMAP_MAX_LUMINANCE = 1e35;

// Radiance as the tone map reads it: NaN/Inf as 0, negatives as 0, at most TONEMAP_MAX_RADIANCE.
vec3 tonemap_input(vec3 c) {
    c = mix(c, vec3(0.0), bvec3(isnan(c.x) || isinf(c.x), isnan(c.y) || isinf(c.y), isnan(c.z) || isinf(c.z)));
    return clamp(c, vec3(0.0), vec3(TONEMAP_MAX_RADIANCE));
}

// Rec.709 luminance (SCENES.md: radiance is linear Rec.709 RGB).
float tonemap_luminance(vec3 c) { return dot(c, vec3(0.2126, 0.7152, 0.0722)); }

// Reinhard et al. 2002, Eq. 4, on the scaled luminance L = scale * Y (scale = exposure * a / L_a,
// Eq. 2), applied to the colour by the ratio L_d / Y. L_d is capped at 65504 before the
// ratio so that a huge L with a small L_white (L^2 / L_white^2 overflows) stays finite: the
// sRGB step clamps at 1 anyway. inv_white2 = 1 / L_white^2 (0: L_white infinite, L/(1+L)).
vec3 tonemap_reinhard(vec3 c, float scale, float inv_white2) {
    float Y = tonemap_luminance(c);
    if (!(Y > 0.0)) return vec3(0.0);
    float L = scale * Y;
    float Ld = min(L / (1.0 + L) * (1.0 + L * inv_white2), 65504.0);
    return c * (Ld / Y);
}
#endif
