#version 450
// Test probe: runs the reference's own GLSL functions on inputs from the debug buffer so
// that tests check the exact code the reference uses against closed-form answers.
// Records are 3 vec4s each. mode 0: BVH vs brute force (in: o, d; out: (t, tri) of both);
// mode 1: deterministic specular path, always transmitting where possible (in: o, d; out:
// final o with w = PHOTON_* outcome, final d with w = bounces, throughput);
// mode 2: Fresnel (in: (cos_i, eta, _, _), (conductor eta rgb), (k rgb);
// out: (F_dielectric, _, _, _), (F_conductor rgb), _);
// mode 3: the driver's loop limit (in: (N, M, _, _): a loop of N iterations, then one of M;
// out: (iterations the first ran, iterations the second ran, _, _)). N and M come from the
// buffer so that neither loop can be unrolled or folded.
#include "sppm.glsl"

void main() {
    uint i = invocation_index();
    if (i >= push.count) return;
    vec4 a = debug_data[3u * i], b = debug_data[3u * i + 1u], c = debug_data[3u * i + 2u];
    if (push.mode == 0u) {
        vec3 d = normalize(b.xyz);
        Hit h1 = trace_triangles(a.xyz, d, 3.4e38);
        Hit h2 = trace_triangles_brute_force(a.xyz, d, 3.4e38);
        debug_data[3u * i] = vec4(h1.kind == 1u ? h1.t : -1.0, uintBitsToFloat(h1.prim), h2.kind == 1u ? h2.t : -1.0, uintBitsToFloat(h2.prim));
    } else if (push.mode == 1u) {
        vec3 o = a.xyz, d = normalize(b.xyz), beta = vec3(1.0);
        uint outcome = PHOTON_LOST;
        uint bounce = 0u;
        for (; bounce <= ref.counts.w; ++bounce) {
            Hit h = trace(o, d, 3.4e38);
            if (h.kind == 0u) { outcome = PHOTON_ESCAPED; break; }
            Surface s = surface_at(o, d, h);
            if (kind_of(materials[s.material]) == MATERIAL_DIFFUSE) { o = s.p; outcome = PHOTON_DEPOSITED; break; }
            if (!specular_step(s, o, d, beta, h.t, -1, 2.0, false)) break;
        }
        debug_data[3u * i] = vec4(o, float(outcome));
        debug_data[3u * i + 1u] = vec4(d, float(bounce));
        debug_data[3u * i + 2u] = vec4(beta, 0.0);
    } else if (push.mode == 3u) {
        uint n = uint(a.x), m = uint(a.y);
        uint first = 0u, second = 0u;
        for (uint k = 0u; k < n; ++k) first += 1u;
        for (uint k = 0u; k < m; ++k) second += 1u;
        debug_data[3u * i] = vec4(float(first), float(second), 0.0, 0.0);
    } else {
        debug_data[3u * i] = vec4(fresnel_dielectric(a.x, a.y), 0.0, 0.0, 0.0);
        debug_data[3u * i + 1u] = vec4(fresnel_conductor(a.x, b.rgb, c.rgb), 0.0);
    }
}
