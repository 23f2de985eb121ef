#version 450
// Test probe: runs the impostor's own GLSL (glsl/include/impostor.glsl, fresnel.glsl) on
// records from a buffer, so that tests check the exact shader code against closed forms.
// Records are 3 vec4s.
//   IMPOSTOR_PROBE_HIT: in (x world, _), (R, _); out (hit point world, 1 if the ray left the
//     impostor), (ray parameter d, |l|/|l'| at the hit, _, _).
//   IMPOSTOR_PROBE_FRESNEL: in (cos_i, _, _, _), (eta rgb, _), (k rgb, _); out (approximate
//     F rgb, _), (exact F rgb, _), unchanged.
#include "prism_shared.glsl"
#include "fresnel.glsl"
#include "impostor.glsl"
layout(constant_id = 0) const uint ITERATIONS = 4;
layout(constant_id = 1) const uint DISTANCE_CHANNEL = 3;
layout(local_size_x = WORKGROUP_2D * WORKGROUP_2D) in;
layout(set = 0, binding = BINDING_IMPOSTOR_PROBE, std430) buffer Records { vec4 records[]; };
layout(set = 0, binding = BINDING_IMPOSTOR_DISTANCE) uniform samplerCube dist_map;
layout(push_constant) uniform ImpostorProbePushBlock { ImpostorProbePush pc; };

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= pc.info.x) return;
    vec4 a = records[3u * i], b = records[3u * i + 1u], c = records[3u * i + 2u];
    if (pc.info.y == IMPOSTOR_PROBE_HIT) {
        vec3 x = a.xyz - pc.reference.xyz;
        vec3 R = normalize(b.xyz);
        float d = impostor_hit_distance(dist_map, DISTANCE_CHANNEL, x, R, ITERATIONS);
        vec3 l = x + R * d;
        bool missed = dot(l, l) > 0.0 && impostor_missed(dist_map, DISTANCE_CHANNEL, l);
        records[3u * i] = vec4(l + pc.reference.xyz, missed ? 1.0 : 0.0);
        records[3u * i + 1u] = vec4(d, impostor_ratio(dist_map, DISTANCE_CHANNEL, l), 0.0, 0.0);
    } else {
        records[3u * i] = vec4(fresnel_conductor_approx(a.x, b.rgb, c.rgb), 0.0);
        records[3u * i + 1u] = vec4(fresnel_conductor(a.x, b.rgb, c.rgb), 0.0);
    }
}
