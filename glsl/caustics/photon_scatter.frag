#version 450
// One photon onto its caustic-texture texel (Hu & Qin 2007 §3.2), summed by additive
// blending: rgb power in W, alpha the photon count.
layout(location = 0) flat in vec4 in_photon;
layout(location = 0) out vec4 out_photon;
void main() {
    out_photon = in_photon;
}
