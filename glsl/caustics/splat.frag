#version 450
// Gaussian point splat of caustics mapping (Shah et al. 2007, §III.F: "textured point
// primitives with a gaussian fall-off"), accumulated by additive blending (§III.C). The
// weights are normalised over the texels the point covers (computed in splat_hits.comp), so each
// splat deposits exactly its vertex's flux into the map: the map holds flux per texel (W).
layout(location = 0) flat in vec3 in_flux;
layout(location = 1) flat in vec3 in_splat;   // xy: centre in texels, z: 1 / (2 sigma^2)
layout(location = 0) out vec4 out_flux;
void main() {
    vec2 o = gl_FragCoord.xy - in_splat.xy;
    out_flux = vec4(in_flux * exp(-dot(o, o) * in_splat.z), 0.0);
}
