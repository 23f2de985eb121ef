//! Where the light simulator's volumes are read (Ihrke et al. 2007, sections 5.2.2 and 5.3):
//! the irradiance and direction volumes are looked up by trilinear interpolation
//! (glsl/eikonal/scatter.glsl `light_at`) at the diffuse surfaces inside them (the floor of
//! Fig. 1 left, what exit rays meet, the impostors around the volume: glsl/eikonal/
//! receiver.glsl) and along view rays through a scattering medium (Eq. 6). Nowhere else: the
//! air a wavefront crosses and the inside of a clear object are never looked up, yet every
//! step of a patch through them deposits there. The deposits that nothing reads are skipped
//! where this mask says so (`render.eikonal.light_deposits = "read"`, glsl/eikonal/
//! light_step.glsl `deposit`); the voxels that are read receive the same deposits as before.
//!
//! A point p reads the voxels whose centres lie within one voxel of it along every axis (the
//! trilinear stencil), and a deposit centred at `at` adds to the eight voxels around it, all
//! within one voxel of the voxel nearest to `at`. So the mask holds, for each voxel w, whether
//! any point that is read lies within two voxels of w's centre along every axis, and the
//! deposit looks up the one voxel nearest to its centre.
use glam::Vec3;

use crate::scene::{Material, Scene, Volume};

/// The world-space triangles of every object whose surface can be lit by the simulation
/// (everything but the clear dielectrics, which the volume stands for and which never
/// receive diffuse light), and the boxes read wholesale: a scattering volume's box, and the
/// light box itself where an animated surface (a heightfield) moves through it.
#[derive(Debug)]
pub struct ReadSites {
    pub triangles: Vec<[Vec3; 3]>,
    pub boxes: Vec<(Vec3, Vec3)>,
}

impl ReadSites {
    /// What reads the light volumes spanning `light_min..light_max` in `scene`, the
    /// simulated `volume` scattering where `scatters`.
    pub fn of_scene(scene: &Scene, volume: &Volume, scatters: bool, light_min: Vec3, light_max: Vec3) -> Self {
        let (mut triangles, mut boxes) = (Vec::new(), Vec::new());
        if scatters {
            boxes.push((volume.min, volume.max));
        }
        for o in &scene.objects {
            if matches!(scene.materials[o.material], Material::Dielectric { .. }) {
                continue;
            }
            if o.heightfield.is_some() {
                // Its waves move it every frame in the window.
                boxes.push((light_min, light_max));
                continue;
            }
            let m = &o.mesh;
            for t in m.indices.chunks_exact(3) {
                let tri = [t[0], t[1], t[2]].map(|k| m.positions[k as usize]);
                let (lo, hi) = (tri[0].min(tri[1]).min(tri[2]), tri[0].max(tri[1]).max(tri[2]));
                if lo.cmple(light_max).all() && hi.cmpge(light_min).all() {
                    triangles.push(tri);
                }
            }
        }
        ReadSites { triangles, boxes }
    }
}

/// One bit per voxel of the grid `resolution` over `min..max` (x fastest, 32 voxels a word):
/// set where a site of `sites` lies within two voxels of the voxel's centre along every axis
/// (see the top). Conservative: a triangle marks every voxel whose box its plane and its
/// bounds both meet, which may include a few beyond its edges.
pub fn read_mask(sites: &ReadSites, min: Vec3, max: Vec3, resolution: [u32; 3]) -> Vec<u32> {
    let [nx, ny, nz] = resolution.map(|r| r as usize);
    let voxel = (max - min) / Vec3::new(nx as f32, ny as f32, nz as f32);
    let reach = 2.0 * voxel;
    let mut bits = vec![0u32; (nx * ny * nz).div_ceil(32).max(1)];
    // The voxels whose centres lie within `reach` of lo..hi along every axis.
    let range = |lo: Vec3, hi: Vec3| {
        let first = ((lo - reach - min) / voxel - 0.5).ceil().max(Vec3::ZERO);
        let last = ((hi + reach - min) / voxel - 0.5).floor().min(Vec3::new(nx as f32, ny as f32, nz as f32) - 1.0);
        (first.as_uvec3(), last, first.cmple(last).all())
    };
    let centre = |x: usize, y: usize, z: usize| min + (Vec3::new(x as f32, y as f32, z as f32) + 0.5) * voxel;
    let mut mark = |lo: Vec3, hi: Vec3, test: &dyn Fn(Vec3) -> bool| {
        let (first, last, any) = range(lo, hi);
        if !any {
            return;
        }
        let last = last.as_uvec3();
        for z in first.z as usize..=last.z as usize {
            for y in first.y as usize..=last.y as usize {
                for x in first.x as usize..=last.x as usize {
                    if test(centre(x, y, z)) {
                        let i = x + nx * (y + ny * z);
                        bits[i / 32] |= 1 << (i % 32);
                    }
                }
            }
        }
    };
    for &(lo, hi) in &sites.boxes {
        mark(lo, hi, &|_| true);
    }
    for t in &sites.triangles {
        let (lo, hi) = (t[0].min(t[1]).min(t[2]), t[0].max(t[1]).max(t[2]));
        let n = (t[1] - t[0]).cross(t[2] - t[0]);
        // The plane meets the box c +- reach where |n . (c - p0)| <= reach . |n|; a
        // degenerate triangle (n = 0) is its bounds.
        let radius = reach.dot(n.abs());
        mark(lo, hi, &|c| n.dot(c - t[0]).abs() <= radius);
    }
    bits
}

/// Whether bit `i` of [`read_mask`]'s words is set.
pub fn is_read(bits: &[u32], i: usize) -> bool {
    bits[i / 32] >> (i % 32) & 1 != 0
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A floor at y = 0 in a grid of 0.1 m voxels from y = -0.23 (centres -0.18 + 0.1 k, none
    /// at a tie): the voxels whose centres are within two voxels (0.2 m) of it are marked,
    /// and no other.
    #[test]
    fn a_floor_marks_the_voxels_within_two_of_it() {
        let (min, max, res) = (Vec3::new(-1.0, -0.23, -1.0), Vec3::new(1.0, 1.77, 1.0), [20, 20, 20]);
        let a = [Vec3::new(-5.0, 0.0, -5.0), Vec3::new(5.0, 0.0, -5.0), Vec3::new(5.0, 0.0, 5.0)];
        let b = [a[0], a[2], Vec3::new(-5.0, 0.0, 5.0)];
        let sites = ReadSites { triangles: vec![a, b], boxes: vec![] };
        let bits = read_mask(&sites, min, max, res);
        for y in 0..20 {
            let centre = -0.23 + (y as f32 + 0.5) * 0.1;
            let expected = y < 4;
            for (x, z) in [(0, 0), (7, 13), (19, 19)] {
                assert_eq!(is_read(&bits, x + 20 * (y + 20 * z)), expected, "voxel ({x}, {y}, {z}), centre y {centre}");
            }
        }
    }

    /// A triangle outside the grid by more than two voxels marks nothing; a box marks its
    /// voxels and two around them.
    #[test]
    fn far_triangles_mark_nothing_and_boxes_their_reach() {
        let (min, max, res) = (Vec3::ZERO, Vec3::ONE, [10, 10, 10]);
        let far = [Vec3::new(0.0, 1.3, 0.0), Vec3::new(1.0, 1.3, 0.0), Vec3::new(0.0, 1.3, 1.0)];
        let sites = ReadSites { triangles: vec![far], boxes: vec![] };
        assert!(read_mask(&sites, min, max, res).iter().all(|&w| w == 0));
        let sites = ReadSites { triangles: vec![], boxes: vec![(Vec3::splat(0.45), Vec3::splat(0.55))] };
        let bits = read_mask(&sites, min, max, res);
        let marked: Vec<usize> = (0..1000).filter(|&i| is_read(&bits, i)).collect();
        // Centres 0.05 + 0.1 k within 0.2 of 0.45..0.55: k = 2..=7 along each axis.
        assert_eq!(marked.len(), 6 * 6 * 6);
        assert!(is_read(&bits, 2 + 10 * (2 + 10 * 2)) && is_read(&bits, 7 + 10 * (7 + 10 * 7)));
    }
}
