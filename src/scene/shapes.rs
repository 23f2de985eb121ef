//! Procedural tessellation of the analytic shapes.
//!
//! Every function returns a [`Mesh`] in the shape's own coordinates (centre included;
//! `mod.rs` applies the object's transform), with exact unit normals and triangles
//! wound counter-clockwise seen from the side the normals point to. Checker
//! coordinates are filled in by the loader except for quads, whose (s, t) are their
//! own edge distances.

use std::f32::consts::{PI, TAU};

use glam::{Mat4, Vec2, Vec3};

use super::mesh::Mesh;

/// Builds a (rows + 1) x (cols + 1) vertex grid from `f(row, col) -> (position,
/// normal)` and triangulates it, orienting each triangle by its vertices' normals.
/// Triangles that collapse to a point or a line (a sphere's poles, a lathe profile
/// point on the axis) are dropped: they cover nothing and only make slivers.
fn grid(rows: u32, cols: u32, f: impl Fn(u32, u32) -> (Vec3, Vec3)) -> Mesh {
    let mut m = Mesh::default();
    for i in 0..=rows {
        for j in 0..=cols {
            let (p, n) = f(i, j);
            m.positions.push(p);
            m.normals.push(n.try_normalize().unwrap_or(Vec3::Y));
        }
    }
    let at = |i: u32, j: u32| i * (cols + 1) + j;
    for i in 0..rows {
        for j in 0..cols {
            let (a, b, c, d) = (at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1));
            for tri in [[a, b, c], [a, c, d]] {
                let [pa, pb, pc] = tri.map(|k| m.positions[k as usize]);
                let cross = (pb - pa).cross(pc - pa);
                let scale = (pb - pa).length_squared().max((pc - pa).length_squared());
                if cross.length() <= 1e-7 * scale || scale == 0.0 {
                    continue;
                }
                let n: Vec3 = tri.iter().map(|&k| m.normals[k as usize]).sum();
                if cross.dot(n) >= 0.0 {
                    m.indices.extend_from_slice(&tri);
                } else {
                    m.indices.extend_from_slice(&[tri[0], tri[2], tri[1]]);
                }
            }
        }
    }
    m.checker_uv = vec![Vec2::ZERO; m.positions.len()];
    m
}

/// A UV sphere: `segments` around the Y axis and `segments / 2` from pole to pole.
pub fn sphere(center: Vec3, radius: f32, segments: u32) -> Mesh {
    let nlon = segments.max(3);
    let nlat = (segments / 2).max(2);
    grid(nlat, nlon, |i, j| {
        let theta = PI * i as f32 / nlat as f32;
        let phi = TAU * j as f32 / nlon as f32;
        // sin(pi) is not exactly 0 in f32; pin the poles so their vertices coincide.
        let s = if i == 0 || i == nlat { 0.0 } else { theta.sin() };
        let y = if i == 0 {
            1.0
        } else if i == nlat {
            -1.0
        } else {
            theta.cos()
        };
        let n = Vec3::new(s * phi.sin(), y, s * phi.cos()).normalize();
        (center + radius * n, n)
    })
}

/// The quad's edge directions (u, v) for unit normal `n`: u = normalize(+Y x n), or
/// +X when n is parallel to Y; v = n x u. So a wall facing +Z has u = +X, v = +Y.
pub fn quad_frame(n: Vec3) -> (Vec3, Vec3) {
    let u = Vec3::Y.cross(n).try_normalize().unwrap_or(Vec3::X);
    let v = n.cross(u);
    (u, v)
}

/// A rectangle of `size` = (extent along u, extent along v), facing `normal` (unit).
/// Checker coordinates are the distances from its centre along u and v.
pub fn quad(center: Vec3, size: Vec2, normal: Vec3) -> Mesh {
    let (u, v) = quad_frame(normal);
    let h = size * 0.5;
    let corners = [Vec2::new(-h.x, -h.y), Vec2::new(h.x, -h.y), Vec2::new(h.x, h.y), Vec2::new(-h.x, h.y)];
    Mesh {
        positions: corners.iter().map(|c| center + c.x * u + c.y * v).collect(),
        normals: vec![normal; 4],
        checker_uv: corners.to_vec(),
        // u x v = n, so (0, 1, 2) is counter-clockwise seen from the front.
        indices: vec![0, 1, 2, 0, 2, 3],
    }
}

/// A closed axis-aligned box with hard edges (four vertices per face).
pub fn cuboid(center: Vec3, size: Vec3) -> Mesh {
    let mut m = Mesh::default();
    for axis in 0..3 {
        for sign in [1.0f32, -1.0] {
            let mut n = Vec3::ZERO;
            n[axis] = sign;
            let (u, v) = quad_frame(n);
            let extent = |d: Vec3| (d * size).abs().max_element();
            let face = quad(center + n * (size[axis] * 0.5), Vec2::new(extent(u), extent(v)), n);
            m.append(&face);
        }
    }
    m
}

/// A torus about the Y axis: `segments` around the axis, `segments / 2` around the tube.
pub fn torus(center: Vec3, major: f32, minor: f32, segments: u32) -> Mesh {
    let nmaj = segments.max(3);
    let nmin = (segments / 2).max(3);
    grid(nmin, nmaj, |i, j| {
        let beta = TAU * i as f32 / nmin as f32;
        let alpha = TAU * j as f32 / nmaj as f32;
        let e = Vec3::new(alpha.sin(), 0.0, alpha.cos());
        let n = beta.cos() * e + beta.sin() * Vec3::Y;
        (center + major * e + minor * n, n)
    })
}

/// A solid of revolution: the polyline `profile` of (r, y) points revolved about the
/// +Y axis through `center`, in `segments` steps. Each profile segment gets its own
/// vertices, so edges at profile vertices are hard; normals are smooth around the
/// axis and constant along a segment, on the right-hand side of the segment's
/// direction in the (r, y) half-plane: (dr, dy) -> (dy, -dr). Walking up an outer
/// wall thus faces outward, across a top rim toward the axis faces up, and down an
/// inner wall faces the axis; list the points so that the material is on the left.
pub fn lathe(center: Vec3, profile: &[Vec2], segments: u32) -> Mesh {
    let n_around = segments.max(3);
    let mut m = Mesh::default();
    for seg in profile.windows(2) {
        let (p0, p1) = (seg[0], seg[1]);
        let d = p1 - p0;
        let side = Vec2::new(d.y, -d.x).normalize_or_zero();
        let part = grid(1, n_around, |i, j| {
            let phi = TAU * j as f32 / n_around as f32;
            let e = Vec3::new(phi.sin(), 0.0, phi.cos());
            let p = if i == 0 { p0 } else { p1 };
            let n = side.x * e + side.y * Vec3::Y;
            (center + p.x * e + p.y * Vec3::Y, n)
        });
        m.append(&part);
    }
    m
}

/// A cylinder wall without caps, base centre `center`, normals outward.
pub fn open_cylinder(center: Vec3, radius: f32, height: f32, segments: u32) -> Mesh {
    lathe(center, &[Vec2::new(radius, 0.0), Vec2::new(radius, height)], segments)
}

/// One travelling sine wave of a heightfield.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Wave {
    pub amplitude: f32,
    pub kx: f32,
    pub kz: f32,
    pub omega: f32,
    pub phase: f32,
}

/// h(x, z) = sum of amplitude * sin(kx x + kz z + omega t + phase).
pub fn wave_height(waves: &[Wave], x: f32, z: f32, time: f32) -> f32 {
    waves.iter().map(|w| w.amplitude * (w.kx * x + w.kz * z + w.omega * time + w.phase).sin()).sum()
}

/// The unit normal of y = h(x, z), facing +Y: normalize(-dh/dx, 1, -dh/dz).
pub fn wave_normal(waves: &[Wave], x: f32, z: f32, time: f32) -> Vec3 {
    let (mut dx, mut dz) = (0.0f32, 0.0f32);
    for w in waves {
        let c = w.amplitude * (w.kx * x + w.kz * z + w.omega * time + w.phase).cos();
        dx += c * w.kx;
        dz += c * w.kz;
    }
    Vec3::new(-dx, 1.0, -dz).normalize()
}

/// A heightfield y = center.y + h(x, z) over `size` = (sx, sz) centred on `center`,
/// `resolution` = (nx, nz) cells. h is evaluated at the shape's own (x, z), centre
/// included, so a pool centred on the origin reads its formula in world coordinates.
#[derive(Debug, Clone, PartialEq)]
pub struct Heightfield {
    pub center: Vec3,
    pub size: Vec2,
    pub resolution: [u32; 2],
    pub waves: Vec<Wave>,
    /// The object's transform, applied after the formula (the loader applies it to
    /// [`Heightfield::mesh`]; the GPU animation applies it per vertex).
    pub transform: Mat4,
}

impl Heightfield {
    /// The grid's vertices, row by row along z: (nx + 1) (nz + 1) of them, the order the
    /// GPU animation (glsl/common/heightfield.comp) writes them in.
    pub fn cells(&self) -> [u32; 2] {
        self.resolution.map(|n| n.max(1))
    }

    /// The surface at `time`, before the transform.
    pub fn mesh(&self, time: f32) -> Mesh {
        let ([nx, nz], c, s) = (self.cells(), self.center, self.size);
        grid(nz, nx, |i, j| {
            let x = c.x + s.x * (j as f32 / nx as f32 - 0.5);
            let z = c.z + s.y * (i as f32 / nz as f32 - 0.5);
            let y = c.y + wave_height(&self.waves, x, z, time);
            (Vec3::new(x, y, z), wave_normal(&self.waves, x, z, time))
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every non-degenerate triangle's winding agrees with its vertex normals, and
    /// every normal is unit length.
    fn check_consistent(m: &Mesh) {
        assert_eq!(m.positions.len(), m.normals.len());
        assert_eq!(m.positions.len(), m.checker_uv.len());
        for n in &m.normals {
            assert!((n.length() - 1.0).abs() < 1e-5, "normal {n}");
        }
        for t in m.indices.chunks_exact(3) {
            let [a, b, c] = [t[0], t[1], t[2]].map(|k| k as usize);
            let cross = (m.positions[b] - m.positions[a]).cross(m.positions[c] - m.positions[a]);
            let n = m.normals[a] + m.normals[b] + m.normals[c];
            assert!(cross.dot(n) > 0.0, "triangle {a},{b},{c} wound against its normals");
        }
    }

    #[test]
    fn sphere_normals_are_exact_and_outward() {
        let c = Vec3::new(1.0, 2.0, 3.0);
        let m = sphere(c, 0.5, 16);
        check_consistent(&m);
        for (p, n) in m.positions.iter().zip(&m.normals) {
            assert!(((*p - c).length() - 0.5).abs() < 1e-5);
            assert!(((*p - c) / 0.5 - *n).length() < 1e-5);
        }
        // 16 x 8 grid less one triangle per cell on each pole row.
        assert_eq!(m.triangle_count(), 16 * 8 * 2 - 2 * 16);
    }

    #[test]
    fn quad_frame_and_normals() {
        let (u, v) = quad_frame(Vec3::Z);
        assert!((u - Vec3::X).length() < 1e-6 && (v - Vec3::Y).length() < 1e-6);
        let (u, v) = quad_frame(Vec3::Y);
        assert!((u - Vec3::X).length() < 1e-6 && (v + Vec3::Z).length() < 1e-6);
        let (u, v) = quad_frame(Vec3::NEG_Y);
        assert!((u - Vec3::X).length() < 1e-6 && (v - Vec3::Z).length() < 1e-6);
        let (u, _) = quad_frame(Vec3::X);
        assert!((u + Vec3::Z).length() < 1e-6);
        let m = quad(Vec3::new(0.0, 2.0, -3.0), Vec2::new(10.0, 6.0), Vec3::Z);
        check_consistent(&m);
        let (lo, hi) = m.bounds();
        assert!((lo - Vec3::new(-5.0, -1.0, -3.0)).length() < 1e-6);
        assert!((hi - Vec3::new(5.0, 5.0, -3.0)).length() < 1e-6);
        assert_eq!(m.checker_uv[0], Vec2::new(-5.0, -3.0));
    }

    #[test]
    fn box_faces_point_outward() {
        let c = Vec3::new(-1.2, 0.4, -1.0);
        let m = cuboid(c, Vec3::splat(0.8));
        check_consistent(&m);
        assert_eq!(m.triangle_count(), 12);
        for (p, n) in m.positions.iter().zip(&m.normals) {
            assert!((*p - c).dot(*n) > 0.39);
        }
        let (lo, hi) = m.bounds();
        assert!((lo - Vec3::new(-1.6, 0.0, -1.4)).length() < 1e-6);
        assert!((hi - Vec3::new(-0.8, 0.8, -0.6)).length() < 1e-6);
    }

    #[test]
    fn torus_normals_point_away_from_the_tube_centre() {
        let m = torus(Vec3::ZERO, 1.0, 0.25, 24);
        check_consistent(&m);
        for (p, n) in m.positions.iter().zip(&m.normals) {
            let ring = Vec3::new(p.x, 0.0, p.z).normalize();
            assert!(((*p - ring) / 0.25 - *n).length() < 1e-4);
        }
    }

    #[test]
    fn lathe_ring_normals_outward_inward_up() {
        let profile = [Vec2::new(1.0, 0.0), Vec2::new(1.0, 0.5), Vec2::new(0.97, 0.5), Vec2::new(0.97, 0.0)];
        let m = lathe(Vec3::ZERO, &profile, 32);
        check_consistent(&m);
        let (mut outer, mut inner, mut top) = (0, 0, 0);
        for (p, n) in m.positions.iter().zip(&m.normals) {
            let radial = Vec3::new(p.x, 0.0, p.z).normalize();
            if n.dot(Vec3::Y) > 0.999 {
                top += 1;
                assert!((p.y - 0.5).abs() < 1e-6);
            } else if n.dot(radial) > 0.999 {
                outer += 1;
                assert!((Vec3::new(p.x, 0.0, p.z).length() - 1.0).abs() < 1e-5);
            } else {
                assert!(n.dot(radial) < -0.999, "normal {n} at {p}");
                inner += 1;
                assert!((Vec3::new(p.x, 0.0, p.z).length() - 0.97).abs() < 1e-5);
            }
        }
        assert_eq!((outer, inner, top), (66, 66, 66));
        let (lo, hi) = m.bounds();
        assert!(lo.y.abs() < 1e-6 && (hi.y - 0.5).abs() < 1e-6);
    }

    #[test]
    fn heightfield_matches_formula() {
        let waves = [
            Wave { amplitude: 0.03, kx: 4.0, kz: 0.0, omega: 3.0, phase: 0.0 },
            Wave { amplitude: 0.02, kx: 0.0, kz: 5.0, omega: -2.0, phase: 1.0 },
        ];
        let h = Heightfield {
            center: Vec3::ZERO,
            size: Vec2::new(6.0, 6.0),
            resolution: [8, 8],
            waves: waves.to_vec(),
            transform: Mat4::IDENTITY,
        };
        let m = h.mesh(0.0);
        check_consistent(&m);
        for p in &m.positions {
            let h = 0.03 * (4.0 * p.x).sin() + 0.02 * (5.0 * p.z + 1.0).sin();
            assert!((p.y - h).abs() < 1e-6);
        }
        // Normal against a finite difference of the formula.
        let (x, z, e) = (0.3f32, -0.7f32, 1e-3f32);
        let h = |x: f32, z: f32| wave_height(&waves, x, z, 0.0);
        let fd = Vec3::new(-(h(x + e, z) - h(x - e, z)) / (2.0 * e), 1.0, -(h(x, z + e) - h(x, z - e)) / (2.0 * e))
            .normalize();
        assert!((fd - wave_normal(&waves, x, z, 0.0)).length() < 1e-3);
    }
}
