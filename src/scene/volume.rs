//! The `[volume]` table: an inhomogeneous refractive volume for eikonal rendering (Ihrke et
//! al. 2007, section 5.1: "input scenes are stored as a set of 3D volume textures"). The
//! scene gives the volume's box, its voxel resolution and an analytic refractive-index
//! profile; [`Volume::sample`] rasterizes the profile at the voxel centres, which the GPU
//! smooths and differentiates (src/technique/eikonal/eikonal_view.rs). Outside the box the index is 1.
use glam::{DVec3, Vec3};

use super::file::{check_keys, FileIndex, FileVolume};
use super::{finite, point, positive, value_err, vec3, SceneError, Source};

/// Largest voxel count along one axis (256^3 f32 voxels are 64 MiB per volume texture).
pub const MAX_VOLUME_RESOLUTION: u32 = 256;

/// Largest refractive index a profile may reach (every real medium is far below).
const MAX_INDEX: f64 = 10.0;

/// An analytic refractive-index field n(x), world space.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum IndexProfile {
    /// n inside the sphere (`center`, `radius`), 1 outside; without a sphere, n in the
    /// whole box.
    Constant { n: f32, sphere: Option<(Vec3, f32)> },
    /// The Luneburg lens: n(r) = sqrt(2 - (r/R)^2) for r <= R, 1 outside. Parallel rays
    /// entering it meet on the far surface, diametrically opposite their entry direction.
    Luneburg { center: Vec3, radius: f32 },
    /// n(x) = n0 + gradient . (x - centre of the bounds) in the whole box.
    Linear { n0: f32, gradient: Vec3, origin: Vec3 },
}

impl IndexProfile {
    /// n at `x` (inside the volume's box).
    pub fn n(&self, x: DVec3) -> f64 {
        match *self {
            IndexProfile::Constant { n, sphere: None } => n as f64,
            IndexProfile::Constant { n, sphere: Some((c, r)) } => {
                if x.distance_squared(c.as_dvec3()) <= (r as f64) * (r as f64) {
                    n as f64
                } else {
                    1.0
                }
            }
            IndexProfile::Luneburg { center, radius } => {
                let q = x.distance_squared(center.as_dvec3()) / (radius as f64 * radius as f64);
                if q <= 1.0 {
                    (2.0 - q).sqrt()
                } else {
                    1.0
                }
            }
            IndexProfile::Linear { n0, gradient, origin } => n0 as f64 + gradient.as_dvec3().dot(x - origin.as_dvec3()),
        }
    }

    /// The analytic gradient of n at `x` (0 across the jump of a constant sphere).
    pub fn gradient(&self, x: DVec3) -> DVec3 {
        match *self {
            IndexProfile::Constant { .. } => DVec3::ZERO,
            IndexProfile::Luneburg { center, radius } => {
                let d = x - center.as_dvec3();
                let r2 = radius as f64 * radius as f64;
                if d.length_squared() <= r2 {
                    // n = sqrt(2 - |d|^2 / R^2)  =>  grad n = -d / (R^2 n).
                    -d / (r2 * self.n(x))
                } else {
                    DVec3::ZERO
                }
            }
            IndexProfile::Linear { gradient, .. } => gradient.as_dvec3(),
        }
    }

    /// The region where the medium is (for absorption): a sphere, or the whole box (`None`).
    pub fn region(&self) -> Option<(Vec3, f32)> {
        match *self {
            IndexProfile::Constant { sphere, .. } => sphere,
            IndexProfile::Luneburg { center, radius } => Some((center, radius)),
            IndexProfile::Linear { .. } => None,
        }
    }
}

#[derive(Debug, Clone, PartialEq)]
pub struct Volume {
    pub name: String,
    pub min: Vec3,
    pub max: Vec3,
    /// Voxels along x, y, z (each 1..=[`MAX_VOLUME_RESOLUTION`]).
    pub resolution: [u32; 3],
    pub index: IndexProfile,
    /// Absorption coefficient sigma_a per metre, RGB, inside the profile's region.
    pub attenuation: Vec3,
    /// The rest of the base material of the profile's region (src/scene/volume_sources.rs):
    /// scattering coefficient per metre, Henyey-Greenstein g, emitted radiance per metre and
    /// the factor on the Fresnel reflectance at its boundary.
    pub sigma_s: Vec3,
    pub hg_g: f32,
    pub emission: Vec3,
    pub reflectance: f32,
    /// `[[volume.region]]`s in file order (later ones override earlier ones).
    pub regions: Vec<super::volume_sources::Region>,
}

impl Volume {
    /// Edge lengths of one voxel.
    pub fn voxel_size(&self) -> Vec3 {
        (self.max - self.min)
            / Vec3::new(self.resolution[0] as f32, self.resolution[1] as f32, self.resolution[2] as f32)
    }

    /// The centre of voxel (i, j, k).
    pub fn voxel_center(&self, i: u32, j: u32, k: u32) -> Vec3 {
        self.min + (Vec3::new(i as f32, j as f32, k as f32) + 0.5) * self.voxel_size()
    }

    /// n - 1 as voxel (centre `x`) stores it. A constant sphere is rasterized from its
    /// implicit function (section 5.1) with a one-voxel linear ramp of the signed distance
    /// across the surface, its coverage, instead of a staircase of inside/outside voxels
    /// whose gradients would scatter the rays.
    pub(super) fn sample_at(&self, x: DVec3) -> f64 {
        match self.index {
            IndexProfile::Constant { n, sphere: Some((c, r)) } => {
                let h = self.voxel_size().as_dvec3().element_sum() / 3.0;
                let distance = x.distance(c.as_dvec3()) - r as f64;
                (n as f64 - 1.0) * (0.5 - distance / h).clamp(0.0, 1.0)
            }
            _ => self.index.n(x) - 1.0,
        }
    }

    /// n - 1 at every voxel centre, x fastest then y then z (the layout of a 3D texture
    /// upload). Stored as the deviation from 1 so that smoothing with the padding of the
    /// surrounding air (n = 1) is exact for n = 1.
    pub fn sample(&self) -> Vec<f32> {
        let [nx, ny, nz] = self.resolution;
        let mut out = Vec::with_capacity((nx * ny * nz) as usize);
        for k in 0..nz {
            for j in 0..ny {
                for i in 0..nx {
                    out.push(self.sample_at(self.voxel_center(i, j, k).as_dvec3()) as f32);
                }
            }
        }
        out
    }
}

pub(super) fn volume(v: &FileVolume, src: &Source) -> Result<Volume, SceneError> {
    let min = point(src, "volume.bounds.min", v.bounds.min)?;
    let max = point(src, "volume.bounds.max", v.bounds.max)?;
    if !min.cmplt(max).all() {
        return Err(value_err(
            src,
            "volume.bounds",
            format!("`bounds.min` {min} must be below `bounds.max` {max} on every axis"),
            "give the box's smallest corner as `min` and its largest as `max`",
        ));
    }
    for (axis, &r) in v.resolution.iter().enumerate() {
        if !(1..=MAX_VOLUME_RESOLUTION).contains(&r) {
            return Err(value_err(
                src,
                "volume.resolution",
                format!("`resolution` must be from 1 to {MAX_VOLUME_RESOLUTION} voxels on every axis, not {r} on axis {axis}"),
                "e.g. resolution = [64, 64, 64] (the paper uses 64^3 to 256^3)",
            ));
        }
    }
    let index = match &v.index {
        Some(f) => index(f, (min + max) * 0.5, src)?,
        // Without a profile the box holds air; regions put the media in.
        None => IndexProfile::Constant { n: 1.0, sphere: None },
    };
    let check_range = |n: f64, path: &str| {
        if n > 0.0 && n <= MAX_INDEX {
            Ok(())
        } else {
            Err(value_err(
                src,
                path,
                format!("the refractive index must stay in (0, {MAX_INDEX}] inside the volume, not {n}"),
                "use an index such as 1.33 (water) or 1.5 (glass)",
            ))
        }
    };
    if let IndexProfile::Linear { .. } = index {
        for c in 0..8 {
            let corner = Vec3::new(
                if c & 1 == 0 { min.x } else { max.x },
                if c & 2 == 0 { min.y } else { max.y },
                if c & 4 == 0 { min.z } else { max.z },
            );
            check_range(index.n(corner.as_dvec3()), "volume.index.gradient")?;
        }
    }
    if let IndexProfile::Constant { n, .. } = index {
        check_range(n as f64, "volume.index.n")?;
    }
    let attenuation = super::volume_sources::coefficient(src, "volume.attenuation", v.attenuation)?;
    let sources = super::volume_sources::sources(v, src)?;
    Ok(Volume {
        name: v.name.clone().unwrap_or_else(|| "volume".into()),
        min,
        max,
        resolution: v.resolution,
        index,
        attenuation,
        sigma_s: sources.sigma_s,
        hg_g: sources.hg_g,
        emission: sources.emission,
        reflectance: sources.reflectance,
        regions: sources.regions,
    })
}

fn index(f: &FileIndex, origin: Vec3, src: &Source) -> Result<IndexProfile, SceneError> {
    let path = "volume.index";
    let what = format!("index type `{}`", f.kind);
    let p = |k: &str| format!("{path}.{k}");
    match f.kind.as_str() {
        "constant" => {
            check_keys(src, path, &what, &f.present(), &["n", "center", "radius"], &["n"])?;
            let n = finite(src, &p("n"), f.n.unwrap_or(1.0))?;
            let sphere = match (f.center, f.radius) {
                (None, None) => None,
                (Some(c), Some(r)) => Some((point(src, &p("center"), c)?, positive(src, &p("radius"), r)?)),
                _ => {
                    return Err(value_err(
                        src,
                        path,
                        "a constant index takes both `center` and `radius` (a sphere) or neither (the whole box)"
                            .into(),
                        "add the missing key or remove the other",
                    ))
                }
            };
            Ok(IndexProfile::Constant { n, sphere })
        }
        "luneburg" => {
            check_keys(src, path, &what, &f.present(), &["center", "radius"], &["center", "radius"])?;
            Ok(IndexProfile::Luneburg {
                center: point(src, &p("center"), f.center.unwrap_or_default())?,
                radius: positive(src, &p("radius"), f.radius.unwrap_or_default())?,
            })
        }
        "linear" => {
            check_keys(src, path, &what, &f.present(), &["n0", "gradient"], &["n0", "gradient"])?;
            Ok(IndexProfile::Linear {
                n0: finite(src, &p("n0"), f.n0.unwrap_or_default())?,
                gradient: vec3(src, &p("gradient"), f.gradient.unwrap_or_default())?,
                origin,
            })
        }
        other => Err(value_err(
            src,
            &p("type"),
            format!("unknown index type `{other}`"),
            "accepted values: `constant`, `luneburg`, `linear`",
        )),
    }
}
