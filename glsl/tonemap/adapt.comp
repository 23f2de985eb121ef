#version 450
// Adaptive tone map, step 2: sum the partial sums of log_average.comp into the log-average
// luminance L_avg (Reinhard et al. 2002, Eq. 1), let the adapted luminance L_a follow it
// (Krawczyk et al. 2005, §2.2 Eq. 5, §2.3 Eq. 7, §3.2 Eq. 12):
//   L_a(t) = L_a(t - T) + (L_avg - L_a(t - T)) (1 - exp(-T / tau)),
//   tau = sigma tau_rod + (1 - sigma) tau_cone, sigma = 0.04 / (0.04 + L_a)  (rods' share)
// with T the time since the last frame (push; T < 0: converged, L_a = L_avg, as for every
// headless render), the key a = 1.03 - 2 / (2 + log10(L_a + 1)) (Krawczyk et al. 2005, Eq. 11)
// unless the scene fixes it, and L_white. Writes the state texels that adaptive.frag reads
// and this frame slot's entry of the host-visible statistics.
#include "adaptive.glsl"
layout(local_size_x = TONEMAP_GROUP * TONEMAP_GROUP) in;
layout(push_constant) uniform Push { AdaptPush p; } push;
layout(set = 0, binding = TONEMAP_BINDING_PARTIALS, std430) readonly buffer Partials { vec2 partials[]; };
// Texel 0: (scale = exposure a luminance_scale / L_a, 1 / L_white^2, L_a, L_avg); texel 1: (a, L_white, max L_w, 0).
layout(set = 0, binding = TONEMAP_BINDING_STATE, rgba32f) uniform image2D state;
// Per frame slot: (L_avg, L_a, a, L_white), read by the host after the slot's fence.
layout(set = 0, binding = TONEMAP_BINDING_STATS, std430) writeonly buffer Stats { vec4 stats[]; };

const uint N = TONEMAP_GROUP * TONEMAP_GROUP;
shared float s_log[N];
shared float s_max[N];

void main() {
    uint i = gl_LocalInvocationIndex;
    float l = 0.0, m = 0.0;
    for (uint g = i; g < push.p.size.z; g += N) {
        vec2 v = partials[g];
        l += v.x;
        m = max(m, v.y);
    }
    s_log[i] = l;
    s_max[i] = m;
    barrier();
    for (uint stride = N / 2u; stride > 0u; stride /= 2u) {
        if (i < stride) {
            s_log[i] += s_log[i + stride];
            s_max[i] = max(s_max[i], s_max[i + stride]);
        }
        barrier();
    }
    if (i != 0u) return;
    float pixels = float(push.p.size.x) * float(push.p.size.y);
    float L_avg = exp(s_log[0] / pixels);
    float dt = push.p.params.x;
    float L_a = L_avg;
    if (dt >= 0.0) {
        float prev = imageLoad(state, ivec2(0, 0)).z;
        // A state that is not a positive finite luminance (never written) starts converged.
        if (prev > 0.0 && !isinf(prev)) {
            float sigma = 0.04 / (0.04 + prev);
            float tau = sigma * push.p.params2.x + (1.0 - sigma) * push.p.params2.y;
            float k = tau > 0.0 ? 1.0 - exp(-dt / tau) : 1.0;
            L_a = prev + (L_avg - prev) * k;
        }
    }
    float a = push.p.params.z > 0.0 ? push.p.params.z : 1.03 - 2.0 / (2.0 + log(L_a + 1.0) / log(10.0));
    // L = exposure a / L_a * L_w (Reinhard et al. 2002, Eq. 2) with L_w = luminance_scale * Y of
    // the radiance: adaptive.frag multiplies the radiance's Y by this scale.
    float scale = push.p.params2.w * a * push.p.params2.z / L_a;
    // Auto L_white: the largest scaled luminance, at least 1 (see TonemapAdaptiveParams).
    float white = push.p.params.w > 0.0 ? push.p.params.w : max(scale * s_max[0] / push.p.params2.z, 1.0);
    float inv_white2 = 1.0 / (white * white);
    imageStore(state, ivec2(0, 0), vec4(scale, inv_white2, L_a, L_avg));
    imageStore(state, ivec2(1, 0), vec4(a, white, s_max[0], 0.0));
    stats[push.p.size.w] = vec4(L_avg, L_a, a, white);
}
