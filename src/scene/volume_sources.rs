//! Volume sources (Ihrke et al. 2007, section 5.1: "the objects in our test scenes were
//! created as solids of revolution, implicit surfaces, or triangle meshes that we rasterized
//! into the 3D volume"), and the per-voxel fields they produce.
//!
//! A `[volume]` holds an analytic index profile (src/scene/volume.rs) with its base material,
//! then any number of `[[volume.region]]`s, each a shape with its own material. Every field
//! is evaluated at the voxel centres on the CPU ([`Volume::fields`]):
//!
//! - implicit shapes (sphere, box, rounded box, cylinder) and solids of revolution (a lathe
//!   profile of (r, y) points about +Y) by their signed distance d, as the coverage
//!   c = clamp(1/2 - d / h, 0, 1) with h the mean voxel edge: a one-voxel linear ramp across
//!   the surface instead of a staircase (the smoothing and gradient of section 5.1 then see
//!   the surface where it is);
//! - triangle meshes by scanline parity: rays along +x through 2 x 2 sub-rows of every voxel
//!   row collect their crossings with the mesh (a 2D point-in-triangle test in (y, z) with
//!   the top-left rule, so a ray through a shared edge or vertex counts exactly one of the
//!   triangles); the non-zero winding rule gives the inside intervals, and a voxel's coverage
//!   is the inside length of its x extent, averaged over the sub-rows. A row whose windings do
//!   not sum to zero proves the mesh is not closed: that is an error.
//!
//! **Override rule:** regions are applied in file order over the profile and its base
//! material; each one blends every field towards its own material by its coverage c,
//! field = (1 - c) field + c region, so a later region replaces what earlier ones put inside
//! it (the wine in a glass, a smoke box around a bunny given before the bunny).
//!
//! Fields (x fastest, then y, then z): the refractive index per RGB channel (stored as n - 1,
//! see [`Volume::sample`]), RGB extinction sigma_a + sigma_s with the Henyey-Greenstein g,
//! the albedo sigma_s / extinction with the surface reflectance factor, RGB emission and the
//! boundary indicator (section 5.1's discrete Dirac delta of Eq. 2): 1 where the unsmoothed
//! index jumps (the surface of a constant sphere, a region boundary that changes n and is
//! not hidden inside a later region, or a box face where the index is not 1), 0 elsewhere.
use std::sync::Arc;

use glam::{DVec2, DVec3, Mat4, Vec2, Vec3};

use super::file::{check_keys, FileObject, FileRegion, Rgb};
use super::mesh::Mesh;
use super::{finite, point, positive, rgb, value_err, vec3, ErrorKind, SceneError, Source};

/// The largest refractive index a region may have (as the profiles).
pub const MAX_REGION_INDEX: f32 = 10.0;
/// The largest extinction or emission: the GPU stores them as 16-bit floats (max 65504).
pub const MAX_COEFFICIENT: f32 = 10_000.0;
/// |g| of Henyey-Greenstein must stay below 1 (g = +-1 is a delta, not a phase function).
pub const MAX_HG_G: f32 = 0.99;
/// Most `[[volume.region]]`s: each is evaluated at every voxel.
pub const MAX_REGIONS: usize = 256;

/// The material of a region (or the profile's base material).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct VolumeMaterial {
    /// Refractive index per RGB channel (different channels: dispersion, section 5.3).
    pub n: Vec3,
    /// Absorption coefficient per metre, RGB.
    pub sigma_a: Vec3,
    /// Scattering coefficient per metre, RGB (rendered by the light branch's single
    /// scattering; here it only adds to the extinction).
    pub sigma_s: Vec3,
    /// Henyey-Greenstein anisotropy.
    pub hg_g: f32,
    /// Emitted radiance per metre of path, RGB (L_e of Eq. 2).
    pub emission: Vec3,
    /// Factor on the Fresnel reflectance at this region's boundary (rho of Eq. 2 is
    /// reflectance x Fresnel; 1: a clean dielectric surface).
    pub reflectance: f32,
}

impl Default for VolumeMaterial {
    fn default() -> Self {
        VolumeMaterial {
            n: Vec3::ONE,
            sigma_a: Vec3::ZERO,
            sigma_s: Vec3::ZERO,
            hg_g: 0.0,
            emission: Vec3::ZERO,
            reflectance: 1.0,
        }
    }
}

/// A region's shape in its own coordinates (the region's transform places it).
#[derive(Debug, Clone, PartialEq)]
pub enum RegionShape {
    Sphere {
        center: Vec3,
        radius: f32,
    },
    /// `half`: half the edge lengths.
    Box {
        center: Vec3,
        half: Vec3,
    },
    RoundedBox {
        center: Vec3,
        half: Vec3,
        radius: f32,
    },
    /// Axis +Y, `center` the centre of the base.
    Cylinder {
        center: Vec3,
        radius: f32,
        height: f32,
    },
    /// The polygon (0, y_first), profile..., (0, y_last) in the (r, y) half-plane revolved
    /// about the +Y axis through `center`.
    Lathe {
        center: Vec3,
        polygon: Vec<DVec2>,
    },
    /// A closed triangle mesh, already in world space.
    Mesh(Arc<Mesh>),
}

#[derive(Debug, Clone, PartialEq)]
pub struct Region {
    pub name: String,
    pub shape: RegionShape,
    /// World to shape coordinates (identity for meshes, placed on load).
    pub inverse: Mat4,
    /// Uniform scale of the transform (shape distances times it are world distances).
    pub scale: f32,
    pub material: VolumeMaterial,
}

impl Region {
    /// Signed distance in metres (negative inside) for the implicit shapes and lathes.
    pub fn distance(&self, x: Vec3) -> f64 {
        let p = self.inverse.transform_point3(x).as_dvec3();
        let d = match &self.shape {
            RegionShape::Sphere { center, radius } => p.distance(center.as_dvec3()) - *radius as f64,
            RegionShape::Box { center, half } => box_sdf(p - center.as_dvec3(), half.as_dvec3()),
            RegionShape::RoundedBox { center, half, radius } => {
                let r = *radius as f64;
                box_sdf(p - center.as_dvec3(), half.as_dvec3() - DVec3::splat(r)) - r
            }
            RegionShape::Cylinder { center, radius, height } => {
                let q = p - center.as_dvec3();
                let h = *height as f64 * 0.5;
                let d = DVec2::new(DVec2::new(q.x, q.z).length() - *radius as f64, (q.y - h).abs() - h);
                d.x.max(d.y).min(0.0) + d.max(DVec2::ZERO).length()
            }
            RegionShape::Lathe { center, polygon } => {
                let q = p - center.as_dvec3();
                polygon_sdf(DVec2::new(DVec2::new(q.x, q.z).length(), q.y), polygon)
            }
            RegionShape::Mesh(_) => f64::INFINITY,
        };
        d * self.scale as f64
    }
}

/// Signed distance to the box of half extents `h` centred at 0.
fn box_sdf(p: DVec3, h: DVec3) -> f64 {
    let q = p.abs() - h;
    q.max(DVec3::ZERO).length() + q.max_element().min(0.0)
}

/// Signed distance to a closed polygon (negative inside; even-odd rule), after I. Quilez.
pub fn polygon_sdf(p: DVec2, v: &[DVec2]) -> f64 {
    let mut d = (p - v[0]).length_squared();
    let mut s = 1.0;
    let mut j = v.len() - 1;
    for i in 0..v.len() {
        let e = v[j] - v[i];
        let w = p - v[i];
        let b = w - e * (w.dot(e) / e.length_squared()).clamp(0.0, 1.0);
        d = d.min(b.length_squared());
        let c = [p.y >= v[i].y, p.y < v[j].y, e.x * w.y > e.y * w.x];
        if c.iter().all(|&x| x) || c.iter().all(|&x| !x) {
            s = -s;
        }
        j = i;
    }
    s * d.sqrt()
}

/// The per-voxel fields of a volume (x fastest, then y, then z).
#[derive(Debug, Clone, PartialEq)]
pub struct VolumeFields {
    pub resolution: [u32; 3],
    /// n - 1 per RGB channel.
    pub index: [Vec<f32>; 3],
    /// True when the channels' indices differ anywhere (dispersion).
    pub dispersive: bool,
    /// (sigma_a + sigma_s RGB, Henyey-Greenstein g).
    pub extinction: Vec<[f32; 4]>,
    /// (sigma_s / extinction RGB (0 where the extinction is 0), surface reflectance factor).
    pub albedo: Vec<[f32; 4]>,
    /// (emission RGB, boundary indicator 0 or 1).
    pub emission: Vec<[f32; 4]>,
    /// Fraction of each voxel inside each region, in file order (for tests and the light
    /// branch's consumers).
    pub coverage: Vec<Vec<f32>>,
}

impl VolumeFields {
    pub fn voxels(&self) -> usize {
        self.resolution.iter().map(|&n| n as usize).product()
    }

    /// The boundary indicator dilated by `radius` voxels (Chebyshev): the band of voxels in
    /// which the smoothed index (Gaussian of `render.eikonal.sigma` voxels, 3 sigma wide)
    /// still changes across a jump. The view renderer applies Fresnel once per band. Also
    /// returns the reflectance factor of the band: at each band voxel the smallest factor of
    /// the boundary voxels within `radius` (elsewhere the field's own), so that a surface's
    /// factor holds across its whole band and not only on its boundary voxels.
    pub fn boundary_band(&self, radius: u32) -> (Vec<f32>, Vec<f32>) {
        let [nx, ny, nz] = self.resolution.map(|n| n as i64);
        let mut band: Vec<f32> = self.emission.iter().map(|e| e[3]).collect();
        let mut refl: Vec<f32> = self
            .emission
            .iter()
            .zip(&self.albedo)
            .map(|(e, a)| if e[3] > 0.0 { a[3] } else { f32::INFINITY })
            .collect();
        let r = radius as i64;
        for axis in 0..3 {
            let (src, src_refl) = (band.clone(), refl.clone());
            for k in 0..nz {
                for j in 0..ny {
                    for i in 0..nx {
                        let idx = |q: [i64; 3]| (q[0] + nx * (q[1] + ny * q[2])) as usize;
                        let p = [i, j, k];
                        let n = [nx, ny, nz][axis];
                        let (mut m, mut lo) = (0.0f32, f32::INFINITY);
                        for o in -r..=r {
                            let mut q = p;
                            q[axis] += o;
                            if (0..n).contains(&q[axis]) {
                                m = m.max(src[idx(q)]);
                                lo = lo.min(src_refl[idx(q)]);
                            }
                        }
                        band[idx(p)] = m;
                        refl[idx(p)] = lo;
                    }
                }
            }
        }
        let refl = refl.iter().zip(&self.albedo).map(|(&r, a)| if r.is_finite() { r } else { a[3] }).collect();
        (band, refl)
    }
}

impl super::Volume {
    /// Evaluates the profile, its base material and every region at the voxel centres.
    pub fn fields(&self) -> VolumeFields {
        let [nx, ny, nz] = self.resolution;
        let count = (nx * ny * nz) as usize;
        let h = self.voxel_size().as_dvec3().element_sum() / 3.0;
        let mut index: [Vec<f32>; 3] =
            [Vec::with_capacity(count), Vec::with_capacity(count), Vec::with_capacity(count)];
        let mut sigma_a = vec![Vec3::ZERO; count];
        let mut sigma_s = vec![Vec3::ZERO; count];
        let mut g = vec![0.0f32; count];
        let mut emission = vec![Vec3::ZERO; count];
        let mut reflectance = vec![self.reflectance; count];
        let mut jump = vec![0.0f32; count];
        // The profile and its base material, where the profile's medium is.
        let base = self.index.region();
        let mut v = 0;
        for k in 0..nz {
            for j in 0..ny {
                for i in 0..nx {
                    let x = self.voxel_center(i, j, k).as_dvec3();
                    let dn = self.sample_at(x) as f32;
                    for c in &mut index {
                        c.push(dn);
                    }
                    let c = match base {
                        Some((centre, r)) => (0.5 - (x.distance(centre.as_dvec3()) - r as f64) / h).clamp(0.0, 1.0),
                        None => 1.0,
                    } as f32;
                    sigma_a[v] = c * self.attenuation;
                    sigma_s[v] = c * self.sigma_s;
                    g[v] = c * self.hg_g;
                    emission[v] = c * self.emission;
                    // The index jumps at a constant sphere's surface (its coverage ramp).
                    if let super::IndexProfile::Constant { n, sphere: Some(_) } = self.index {
                        if n != 1.0 && c > 0.0 && c < 1.0 {
                            jump[v] = 1.0;
                        }
                    }
                    v += 1;
                }
            }
        }
        let mut coverages = Vec::with_capacity(self.regions.len());
        for region in &self.regions {
            let cov = match &region.shape {
                RegionShape::Mesh(mesh) => mesh_coverage(mesh, self.min, self.max, self.resolution).0,
                _ => {
                    let mut cov = Vec::with_capacity(count);
                    for k in 0..nz {
                        for j in 0..ny {
                            for i in 0..nx {
                                let d = region.distance(self.voxel_center(i, j, k));
                                cov.push((0.5 - d / h).clamp(0.0, 1.0) as f32);
                            }
                        }
                    }
                    cov
                }
            };
            let m = region.material;
            let dn = m.n - Vec3::ONE;
            let idx = |i: u32, j: u32, k: u32| (i + nx * (j + ny * k)) as usize;
            for k in 0..nz {
                for j in 0..ny {
                    for i in 0..nx {
                        let v = idx(i, j, k);
                        let c = cov[v];
                        if c <= 0.0 {
                            continue;
                        }
                        let old = Vec3::new(index[0][v], index[1][v], index[2][v]);
                        // A boundary of this region that changes the index: a partly covered
                        // voxel, or a fully covered one next to an uncovered one.
                        let changes = (dn - old).abs().max_element() > 1e-6;
                        let edge = c < 1.0
                            || [(1i32, 0i32, 0i32), (0, 1, 0), (0, 0, 1)].iter().any(|&(a, b, e)| {
                                [-1i32, 1].iter().any(|&s| {
                                    let (p, q, r) = (i as i32 + s * a, j as i32 + s * b, k as i32 + s * e);
                                    p >= 0
                                        && q >= 0
                                        && r >= 0
                                        && (p as u32) < nx
                                        && (q as u32) < ny
                                        && (r as u32) < nz
                                        && cov[idx(p as u32, q as u32, r as u32)] < 1.0
                                })
                            });
                        if changes && edge {
                            jump[v] = 1.0;
                        } else if c >= 1.0 && !edge {
                            // Deep inside this region: whatever jumped here before is hidden.
                            jump[v] = 0.0;
                        }
                        if c < 1.0 || edge {
                            reflectance[v] = m.reflectance;
                        }
                        let new = old.lerp(dn, c);
                        index[0][v] = new.x;
                        index[1][v] = new.y;
                        index[2][v] = new.z;
                        sigma_a[v] = sigma_a[v].lerp(m.sigma_a, c);
                        sigma_s[v] = sigma_s[v].lerp(m.sigma_s, c);
                        g[v] += (m.hg_g - g[v]) * c;
                        emission[v] = emission[v].lerp(m.emission, c);
                    }
                }
            }
            coverages.push(cov);
        }
        // Whatever fills the box's faces jumps to the air outside (n = 1).
        for k in 0..nz {
            for j in 0..ny {
                for i in 0..nx {
                    let border = i == 0 || j == 0 || k == 0 || i + 1 == nx || j + 1 == ny || k + 1 == nz;
                    let v = (i + nx * (j + ny * k)) as usize;
                    if border && (0..3).any(|c| index[c][v].abs() > 1e-4) {
                        jump[v] = 1.0;
                    }
                }
            }
        }
        let dispersive = (0..count).any(|v| index[0][v] != index[1][v] || index[1][v] != index[2][v]);
        let extinction: Vec<[f32; 4]> = (0..count)
            .map(|v| {
                let e = sigma_a[v] + sigma_s[v];
                [e.x, e.y, e.z, g[v]]
            })
            .collect();
        let albedo = (0..count)
            .map(|v| {
                let e = sigma_a[v] + sigma_s[v];
                let a = Vec3::select(e.cmpgt(Vec3::ZERO), sigma_s[v] / e.max(Vec3::splat(1e-30)), Vec3::ZERO);
                [a.x, a.y, a.z, reflectance[v]]
            })
            .collect();
        let emission = (0..count).map(|v| emission[v].extend(jump[v]).to_array()).collect();
        VolumeFields {
            resolution: self.resolution,
            index,
            dispersive,
            extinction,
            albedo,
            emission,
            coverage: coverages,
        }
    }
}

/// A 2D orientation test: > 0 when `c` is left of a -> b.
fn orient(a: DVec2, b: DVec2, c: DVec2) -> f64 {
    (b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x)
}

/// The top-left rule for an edge a -> b of a counter-clockwise triangle: a point exactly on
/// it counts as inside only for "top" or "left" edges, so that of two triangles sharing the
/// edge exactly one contains the point.
fn top_left(a: DVec2, b: DVec2) -> bool {
    let e = b - a;
    e.y < 0.0 || (e.y == 0.0 && e.x > 0.0)
}

/// Scanline voxelization of a closed mesh (module doc): the coverage of every voxel of the
/// grid `min`..`max` at `res`, and the number of sub-rows whose windings do not sum to 0
/// (rays proving the mesh is open; 0 for a closed mesh).
pub fn mesh_coverage(mesh: &Mesh, min: Vec3, max: Vec3, res: [u32; 3]) -> (Vec<f32>, usize) {
    let [nx, ny, nz] = res.map(|n| n as usize);
    let (min, max) = (min.as_dvec3(), max.as_dvec3());
    let voxel = (max - min) / DVec3::new(nx as f64, ny as f64, nz as f64);
    // 2 x 2 sub-rows per voxel row, at the quarter points.
    let (ry, rz) = (2 * ny, 2 * nz);
    let row_y = |j: usize| min.y + (j as f64 + 0.5) * 0.5 * voxel.y;
    let row_z = |k: usize| min.z + (k as f64 + 0.5) * 0.5 * voxel.z;
    let mut rows: Vec<Vec<(f64, i32)>> = vec![Vec::new(); ry * rz];
    for t in mesh.indices.chunks_exact(3) {
        let p = [0, 1, 2].map(|i| mesh.positions[t[i] as usize].as_dvec3());
        let q = p.map(|v| DVec2::new(v.y, v.z));
        let area = orient(q[0], q[1], q[2]);
        if area == 0.0 {
            continue; // parallel to the rays: never crossed
        }
        // Counter-clockwise in (y, z); the sign is the crossing's winding direction.
        let (a, b, c, pa, pb, pc, sign) =
            if area > 0.0 { (q[0], q[1], q[2], p[0], p[1], p[2], 1) } else { (q[0], q[2], q[1], p[0], p[2], p[1], -1) };
        let lo = a.min(b).min(c);
        let hi = a.max(b).max(c);
        let j0 = (((lo.x - min.y) / (0.5 * voxel.y) - 0.5).ceil().max(0.0)) as usize;
        let j1 = (((hi.x - min.y) / (0.5 * voxel.y) - 0.5).floor()).min(ry as f64 - 1.0);
        let k0 = (((lo.y - min.z) / (0.5 * voxel.z) - 0.5).ceil().max(0.0)) as usize;
        let k1 = (((hi.y - min.z) / (0.5 * voxel.z) - 0.5).floor()).min(rz as f64 - 1.0);
        if j1 < 0.0 || k1 < 0.0 {
            continue;
        }
        let area = area.abs();
        for k in k0..=k1 as usize {
            for j in j0..=j1 as usize {
                let s = DVec2::new(row_y(j), row_z(k));
                let (w0, w1, w2) = (orient(b, c, s), orient(c, a, s), orient(a, b, s));
                let inside = |w: f64, e0: DVec2, e1: DVec2| w > 0.0 || (w == 0.0 && top_left(e0, e1));
                if inside(w0, b, c) && inside(w1, c, a) && inside(w2, a, b) {
                    let x = (w0 * pa.x + w1 * pb.x + w2 * pc.x) / area;
                    rows[j + ry * k].push((x, sign));
                }
            }
        }
    }
    let mut coverage = vec![0.0f32; nx * ny * nz];
    let mut open = 0;
    for k in 0..rz {
        for j in 0..ry {
            let row = &mut rows[j + ry * k];
            if row.is_empty() {
                continue;
            }
            row.sort_by(|a, b| a.0.total_cmp(&b.0));
            if row.iter().map(|r| r.1).sum::<i32>() != 0 {
                open += 1;
                continue;
            }
            let (vj, vk) = (j / 2, k / 2);
            let mut winding = 0;
            for w in 0..row.len() {
                winding += row[w].1;
                if winding == 0 || w + 1 == row.len() {
                    continue;
                }
                // Inside from row[w].0 to row[w + 1].0: add the overlap with each voxel.
                let (x0, x1) = (row[w].0, row[w + 1].0);
                let i0 = ((x0 - min.x) / voxel.x).floor().max(0.0) as usize;
                let i1 = (((x1 - min.x) / voxel.x).floor() as i64).min(nx as i64 - 1);
                for i in i0..=i1.max(-1) as usize {
                    if i >= nx {
                        break;
                    }
                    let (a, b) = (min.x + i as f64 * voxel.x, min.x + (i + 1) as f64 * voxel.x);
                    let overlap = (x1.min(b) - x0.max(a)).max(0.0) / voxel.x;
                    coverage[i + nx * (vj + ny * vk)] += 0.25 * overlap as f32;
                }
            }
        }
    }
    for c in &mut coverage {
        *c = c.clamp(0.0, 1.0);
    }
    (coverage, open)
}

/// `[volume]`'s base material and `[[volume.region]]`s.
pub(super) struct Sources {
    pub sigma_s: Vec3,
    pub hg_g: f32,
    pub emission: Vec3,
    pub reflectance: f32,
    pub regions: Vec<Region>,
}

pub(super) fn coefficient(src: &Source, path: &str, c: Option<Rgb>) -> Result<Vec3, SceneError> {
    let Some(c) = c else { return Ok(Vec3::ZERO) };
    let v = rgb(src, path, c, false)?;
    if v.max_element() > MAX_COEFFICIENT {
        return Err(value_err(
            src,
            path,
            format!(
                "`{}` must be at most {MAX_COEFFICIENT} per metre, not {v}",
                path.rsplit('.').next().unwrap_or(path)
            ),
            "the volume stores it as a 16-bit float; an opaque medium needs far less (1000 /m: 1 mm deep)",
        ));
    }
    Ok(v)
}

fn hg(src: &Source, path: &str, g: Option<f32>) -> Result<f32, SceneError> {
    let g = finite(src, path, g.unwrap_or(0.0))?;
    if g.abs() > MAX_HG_G {
        return Err(value_err(
            src,
            path,
            format!("`hg_g` must be from -{MAX_HG_G} to {MAX_HG_G}, not {g}"),
            "Henyey-Greenstein's g: 0 isotropic, > 0 forward, < 0 backward scattering",
        ));
    }
    Ok(g)
}

fn reflectance(src: &Source, path: &str, r: Option<f32>) -> Result<f32, SceneError> {
    let r = finite(src, path, r.unwrap_or(1.0))?;
    if !(0.0..=1.0).contains(&r) {
        return Err(value_err(
            src,
            path,
            format!("`reflectance` must be from 0 to 1, not {r}"),
            "a factor on the Fresnel reflectance: 1 a clean surface, 0 none",
        ));
    }
    Ok(r)
}

pub(super) fn sources(v: &super::file::FileVolume, src: &Source) -> Result<Sources, SceneError> {
    super::check_count(src, "volume.region", v.region.len(), MAX_REGIONS)?;
    let regions = v.region.iter().enumerate().map(|(i, r)| region(r, i, src)).collect::<Result<Vec<_>, _>>()?;
    Ok(Sources {
        sigma_s: coefficient(src, "volume.sigma_s", v.sigma_s)?,
        hg_g: hg(src, "volume.hg_g", v.hg_g)?,
        emission: coefficient(src, "volume.emission", v.emission)?,
        reflectance: reflectance(src, "volume.reflectance", v.reflectance)?,
        regions,
    })
}

const REGION_SHAPES: &[&str] = &["sphere", "box", "rounded_box", "cylinder", "lathe", "mesh"];

fn region(r: &FileRegion, i: usize, src: &Source) -> Result<Region, SceneError> {
    let path = format!("volume.region.{i}");
    let p = |k: &str| format!("{path}.{k}");
    let shape = r.shape.as_str();
    let (allowed, required): (&[&str], &[&str]) = match shape {
        "sphere" => (&["center", "radius"], &["radius"]),
        "box" => (&["center", "size"], &["size"]),
        "rounded_box" => (&["center", "size", "radius"], &["size", "radius"]),
        "cylinder" => (&["center", "radius", "height"], &["radius", "height"]),
        "lathe" => (&["center", "profile"], &["profile"]),
        "mesh" => (&["file", "fit"], &["file"]),
        other => {
            return Err(value_err(
                src,
                &p("shape"),
                format!("unknown region shape `{other}`"),
                &format!("accepted shapes: {}", REGION_SHAPES.join(", ")),
            ))
        }
    };
    check_keys(src, &path, &format!("region shape `{shape}`"), &r.present(), allowed, required)?;

    // The material.
    let n = match r.n {
        Some(n) => vec3(src, &p("n"), n.0)?,
        None => Vec3::ONE,
    };
    // `!(x > 0)` also rejects NaN.
    #[allow(clippy::neg_cmp_op_on_partial_ord)]
    if !(n.min_element() > 0.0) || n.max_element() > MAX_REGION_INDEX {
        return Err(value_err(
            src,
            &p("n"),
            format!("the refractive index must be in (0, {MAX_REGION_INDEX}] in every channel, not {n}"),
            "e.g. n = 1.5 (glass) or n = [1.51, 1.52, 1.53] (a dispersive glass, per RGB channel)",
        ));
    }
    let material = VolumeMaterial {
        n,
        sigma_a: coefficient(src, &p("sigma_a"), r.sigma_a)?,
        sigma_s: coefficient(src, &p("sigma_s"), r.sigma_s)?,
        hg_g: hg(src, &p("hg_g"), r.hg_g)?,
        emission: coefficient(src, &p("emission"), r.emission)?,
        reflectance: reflectance(src, &p("reflectance"), r.reflectance)?,
    };

    let (matrix, rotation, scale) = super::transform(src, &path, r.transform.as_ref())?;
    let center = point(src, &p("center"), r.center.unwrap_or_default())?;
    let size = |src: &Source| -> Result<Vec3, SceneError> {
        let s = vec3(src, &p("size"), r.size.unwrap_or_default())?;
        for c in s.to_array() {
            positive(src, &p("size"), c)?;
        }
        Ok(s)
    };
    let shape = match shape {
        "sphere" => RegionShape::Sphere { center, radius: positive(src, &p("radius"), r.radius.unwrap_or_default())? },
        "box" => RegionShape::Box { center, half: 0.5 * size(src)? },
        "rounded_box" => {
            let half = 0.5 * size(src)?;
            let radius = positive(src, &p("radius"), r.radius.unwrap_or_default())?;
            if radius > half.min_element() {
                return Err(value_err(
                    src,
                    &p("radius"),
                    format!("the rounding `radius` {radius} exceeds half the smallest edge {}", half.min_element()),
                    "use a radius at most half the box's smallest `size`",
                ));
            }
            RegionShape::RoundedBox { center, half, radius }
        }
        "cylinder" => RegionShape::Cylinder {
            center,
            radius: positive(src, &p("radius"), r.radius.unwrap_or_default())?,
            height: positive(src, &p("height"), r.height.unwrap_or_default())?,
        },
        "lathe" => RegionShape::Lathe {
            center,
            polygon: lathe_polygon(r.profile.as_deref().unwrap_or(&[]), &p("profile"), src)?,
        },
        _ => {
            let o = FileObject {
                name: None,
                material: String::new(),
                shape: "mesh".into(),
                transform: r.transform.clone(),
                center: None,
                radius: None,
                segments: None,
                size: None,
                normal: None,
                major_radius: None,
                minor_radius: None,
                height: None,
                profile: None,
                resolution: None,
                waves: None,
                time: None,
                file: r.file.clone(),
                fit: r.fit.clone(),
            };
            let mut mesh = super::mesh_object(&o, &path, rotation, src)?;
            if r.fit.is_none() {
                mesh.transform(matrix);
            }
            if mesh.triangle_count() == 0 {
                return Err(src.error(
                    ErrorKind::Mesh,
                    &p("file"),
                    "the region's mesh has no triangles".into(),
                    "a region mesh must be a closed triangle mesh".into(),
                ));
            }
            // Closedness: scanline rays through a grid around the mesh must each leave it
            // as often as they enter (module doc).
            let (lo, hi) = mesh.bounds();
            let pad = (hi - lo).max(Vec3::splat(1e-3)) * 0.01;
            let (_, open) = mesh_coverage(&mesh, lo - pad, hi + pad, [4, 32, 32]);
            if open > 0 {
                return Err(src.error(
                    ErrorKind::Mesh,
                    &p("file"),
                    format!(
                        "the region's mesh is not closed: {open} of 4096 test rays enter it more often than they leave"
                    ),
                    "a region mesh must be watertight (inside and outside are defined by crossings); close its holes"
                        .into(),
                ));
            }
            return Ok(Region {
                name: r.name.clone().unwrap_or_else(|| path.clone()),
                shape: RegionShape::Mesh(Arc::new(mesh)),
                inverse: Mat4::IDENTITY,
                scale: 1.0,
                material,
            });
        }
    };
    Ok(Region { name: r.name.clone().unwrap_or(path), shape, inverse: matrix.inverse(), scale, material })
}

/// A lathe profile (at least two (r, y) points, r >= 0) closed by the axis into the polygon
/// (0, y_first), profile..., (0, y_last); repeated points are dropped.
fn lathe_polygon(profile: &[[f32; 2]], path: &str, src: &Source) -> Result<Vec<DVec2>, SceneError> {
    super::check_count(src, path, profile.len(), super::MAX_PROFILE_POINTS)?;
    if profile.len() < 2 {
        return Err(value_err(
            src,
            path,
            format!("a lathe profile needs at least 2 (r, y) points, not {}", profile.len()),
            "e.g. profile = [[0.5, 0], [0.5, 1]] (a cylinder of radius 0.5 and height 1)",
        ));
    }
    let mut pts = Vec::new();
    for (i, &[r, y]) in profile.iter().enumerate() {
        let q = Vec2::new(r, y);
        if !q.is_finite() || r < 0.0 {
            return Err(value_err(
                src,
                path,
                format!("profile point {i} ({r}, {y}) must be finite with radius r >= 0"),
                "give each point as [r, y], r the distance from the +Y axis",
            ));
        }
        pts.push(q.as_dvec2());
    }
    let mut poly = vec![DVec2::new(0.0, pts[0].y)];
    poly.extend(pts.iter().copied());
    poly.push(DVec2::new(0.0, pts[pts.len() - 1].y));
    poly.dedup_by(|a, b| a.distance(*b) < 1e-9);
    if poly.len() > 1 && poly[0].distance(poly[poly.len() - 1]) < 1e-9 {
        poly.pop();
    }
    let area: f64 = (0..poly.len()).map(|i| poly[i].perp_dot(poly[(i + 1) % poly.len()])).sum::<f64>() * 0.5;
    if poly.len() < 3 || area.abs() < 1e-12 {
        return Err(value_err(
            src,
            path,
            "the lathe profile, closed by the axis, encloses no area".into(),
            "a region must have volume: e.g. profile = [[0.5, 0], [0.5, 1]]",
        ));
    }
    Ok(poly)
}
