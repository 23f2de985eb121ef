#version 450
// The window's water animation: a heightfield's vertices at a new time, written over its
// range of the scene's vertex buffer. The same surface as the scene loader's
// (src/scene/shapes.rs, Heightfield::mesh, then the object's transform and the checker's
// world (x, z)): y = center.y + sum_k a_k sin(kx_k x + kz_k z + omega_k t + phase_k) on an
// nx x nz grid, with the normal normalize(-dh/dx, 1, -dh/dz).
#include "prism_shared.glsl"
layout(local_size_x = WORKGROUP_2D, local_size_y = WORKGROUP_2D) in;


layout(set = 0, binding = HEIGHTFIELD_BINDING_FIELDS, std430) readonly buffer Fields { GpuHeightfield fields[]; };
// Per wave: (amplitude, kx, kz, omega), (phase, 0, 0, 0).
layout(set = 0, binding = HEIGHTFIELD_BINDING_WAVES, std430) readonly buffer Waves { vec4 waves[]; };
// The scene's vertices: position xyz, normal xyz, checker uv.
layout(set = 0, binding = HEIGHTFIELD_BINDING_VERTICES, std430) writeonly buffer Vertices { float vertices[]; };
layout(push_constant) uniform HeightfieldPushBlock { HeightfieldPush push; };

void main() {
    GpuHeightfield f = fields[push.field];
    uint nx = uint(f.size_cells.z), nz = uint(f.size_cells.w);
    uint j = gl_GlobalInvocationID.x, i = gl_GlobalInvocationID.y;
    if (j > nx || i > nz) {
        return;
    }
    float x = f.center.x + f.size_cells.x * (float(j) / float(nx) - 0.5);
    float z = f.center.z + f.size_cells.y * (float(i) / float(nz) - 0.5);
    float h = 0.0, dx = 0.0, dz = 0.0;
    for (uint k = 0u; k < f.ranges.z; ++k) {
        vec4 w = waves[2u * (f.ranges.y + k)];
        float phase = waves[2u * (f.ranges.y + k) + 1u].x;
        float arg = w.y * x + w.z * z + w.w * push.time + phase;
        h += w.x * sin(arg);
        float c = w.x * cos(arg);
        dx += c * w.y;
        dz += c * w.z;
    }
    vec3 p = (f.transform * vec4(x, f.center.y + h, z, 1.0)).xyz;
    vec3 n = normalize(vec3(-dx, 1.0, -dz));
    vec3 m = mat3(f.normal_matrix) * n;
    n = dot(m, m) > 0.0 ? normalize(m) : n;
    uint v = 8u * (f.ranges.x + i * (nx + 1u) + j);
    vertices[v + 0u] = p.x;
    vertices[v + 1u] = p.y;
    vertices[v + 2u] = p.z;
    vertices[v + 3u] = n.x;
    vertices[v + 4u] = n.y;
    vertices[v + 5u] = n.z;
    vertices[v + 6u] = p.x;
    vertices[v + 7u] = p.z;
}
