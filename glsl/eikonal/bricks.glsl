// The uniform-region map of src/technique/eikonal/volume.rs `uniform_reach`: per brick of
// BRICK^3 voxels of a box, the Chebyshev distance in bricks to the nearest brick that is not
// uniform (0: this one is not). Where it is k, the cube of 2k - 1 bricks around the brick has
// a constant smoothed index (no gradient, as far as any field lookup reads) and no material,
// so a ray crosses it on a straight line. Before including, define `uint brick_reach(int i)`
// (the map, x fastest) and BRICK.

#include "cube.glsl"

// How far the ray at x with unit direction d may go straight: to the edge of the cube of
// uniform bricks around x, within the box [box_min, box_max] of `size` voxels; 0 where x's
// brick is not uniform or x is outside the box.
float uniform_leap(vec3 x, vec3 d, vec3 box_min, vec3 box_max, ivec3 size) {
    ivec3 nb = (size + int(BRICK) - 1) / int(BRICK);
    vec3 voxel = (box_max - box_min) / vec3(size);
    vec3 brick = voxel * float(BRICK);
    ivec3 b = ivec3(floor((x - box_min) / brick));
    if (any(lessThan(b, ivec3(0))) || any(greaterThanEqual(b, nb))) return 0.0;
    return cube_exit(x, d, box_min, box_max, b, int(brick_reach(b.x + nb.x * (b.y + nb.y * b.z))), brick, 0.0);
}
