#version 450
// The filter of Hu & Qin 2007 §3.2 over the photon counts p of TEX_CAUSTICS_i:
//   c(u, v) = s * sum_{i,j=-k..k} p(u+i, v+j) sqrt(1 + 2k^2 - (i^2 + j^2)),
// with s an arbitrary brightness (the paper's 0.01). PHOTON_PAPER computes exactly this from
// the counts (alpha), as a grey intensity. PHOTON_PHYSICAL divides the same kernel by its sum
// W (so it conserves energy: sum_uv c(u, v) A = the photons' total power, A the texel's area
// on the rectangle) and applies it to the photons' power (rgb) instead of their count,
// giving irradiance in W/m^2 on the rectangle; alpha holds the normalised count.
// Texels outside the texture contribute nothing.
#include "prism_shared.glsl"
layout(set = 0, binding = 0) uniform sampler2DArray counts;
layout(push_constant) uniform PhotonFilterPushBlock { PhotonFilterPush pc; };
layout(location = 0) in vec2 in_uv;
layout(location = 0) out vec4 out_caustic;

void main() {
    ivec2 size = textureSize(counts, 0).xy;
    ivec2 at = ivec2(gl_FragCoord.xy);
    int k = pc.info.y;
    float k2 = float(2 * k * k);
    vec4 sum = vec4(0.0);
    float weights = 0.0;
    for (int j = -k; j <= k; ++j) {
        for (int i = -k; i <= k; ++i) {
            float w = sqrt(1.0 + k2 - float(i * i + j * j));
            weights += w;
            ivec2 q = at + ivec2(i, j);
            if (any(lessThan(q, ivec2(0))) || any(greaterThanEqual(q, size))) continue;
            sum += w * texelFetch(counts, ivec3(q, pc.info.x), 0);
        }
    }
    if (pc.info.z == int(PHOTON_PAPER)) {
        out_caustic = vec4(vec3(pc.params.x * sum.a), pc.params.x * sum.a);
    } else {
        out_caustic = vec4(sum.rgb / (weights * pc.params.y), sum.a / weights);
    }
}
