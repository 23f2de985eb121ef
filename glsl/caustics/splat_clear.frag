#version 450
// Clears one caustic-atlas layer before its splats (glsl/caustics/splat_layers.comp decides
// which layers need it): zero flux.
layout(location = 0) out vec4 out_flux;
void main() {
    out_flux = vec4(0.0);
}
