#version 450
// One photon's share of the filtered caustic texture (Hu & Qin 2007 §3.2, see
// photon_scatter.vert), summed by additive blending. PHOTON_PAPER: the paper's grey
// s * w(i, j) per photon counted. PHOTON_PHYSICAL divides the kernel by its sum W (so it
// conserves energy: sum_uv c(u, v) A = the photons' total power, A the texel's area on the
// rectangle) and applies it to the photon's power (rgb) instead of its count, giving
// irradiance in W/m^2 on the rectangle; alpha holds the normalised count.
#include "prism_shared.glsl"
layout(push_constant) uniform PhotonScatterPushBlock { PhotonScatterPush pc; };
layout(location = 0) flat in vec4 in_photon;
layout(location = 1) flat in ivec2 in_texel;
layout(location = 0) out vec4 out_caustic;

float kernel(ivec2 o, int k) {
    return sqrt(1.0 + float(2 * k * k) - float(o.x * o.x + o.y * o.y));
}

void main() {
    int k = int(pc.info.w);
    float w = kernel(ivec2(gl_FragCoord.xy) - in_texel, k);
    // in_photon.a: the photons counted (1, or a texel's count with MERGED).
    if (uint(pc.params.w + 0.5) == PHOTON_PAPER) {
        out_caustic = vec4(pc.params.x * w * in_photon.a);
        return;
    }
    float weights = pc.params.y;
    out_caustic = vec4(in_photon.rgb * w / (weights * pc.params.x), w / weights * in_photon.a);
}
