// The cube around a cell of a reach map (a Chebyshev distance per cell to the nearest cell
// that does not qualify): bricks.glsl's uniform-region map, view.frag's weak-gradient map.

// How far the ray at x with unit direction d goes inside the cube of 2k - 1 cells of edge
// `cell` centred on x's cell b (a map's cell of reach k), each face moved `inset` cells in,
// clipped to the box; 0 for k = 0. x must be inside the cube.
float cube_exit(vec3 x, vec3 d, vec3 box_min, vec3 box_max, ivec3 b, int k, vec3 cell, float inset) {
    if (k == 0) return 0.0;
    vec3 lo = max(box_min + (vec3(b - (k - 1)) + inset) * cell, box_min);
    vec3 hi = min(box_min + (vec3(b + k) - inset) * cell, box_max);
    vec3 inv = 1.0 / mix(vec3(1e-30), d, greaterThan(abs(d), vec3(1e-30)));
    vec3 t = max((lo - x) * inv, (hi - x) * inv);
    return max(min(min(t.x, t.y), t.z), 0.0);
}
