#ifndef PRISM_COLOR_GLSL
#define PRISM_COLOR_GLSL
// The sRGB opto-electronic transfer function (IEC 61966-2-1), per SCENES.md's PNG rule.
vec3 srgb_oetf(vec3 c) {
    c = clamp(c, 0.0, 1.0);
    return mix(12.92 * c, 1.055 * pow(c, vec3(1.0 / 2.4)) - 0.055, step(vec3(0.0031308), c));
}
#endif
