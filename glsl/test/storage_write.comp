#version 450
// Test-only kernel: writes (or reads and rewrites) a storage buffer. Two dispatches of it
// with the barrier between them removed is a read-after-write hazard that synchronization
// validation must report (tests/validation.rs).
layout(local_size_x = 64) in;
layout(set = 0, binding = 0, std430) buffer Data { uint values[]; };
void main() {
    values[gl_GlobalInvocationID.x] = values[gl_GlobalInvocationID.x] * 3u + 1u;
}
