//! The scene's GPU-side data: one vertex and index buffer for every object (baked to world
//! space by the scene loader), the material table, the environment map, the irradiance of
//! the environment for diffuse surfaces, and the light records with their shadow projections.
use std::sync::Arc;

use glam::{Mat4, Vec3};

use crate::gpu::{vk, Buffer, BufferView, GpuContext, GpuError, GpuResult, Image, ImageDesc, MemoryLocation};
use crate::graph::{FrameGraph, ImageId};
use crate::scene::{Albedo, Environment, Light, Material, Scene};
use crate::{ENVIRONMENT_GRID_ALPHA, MAX_LIGHTS, MAX_MATERIALS, SHADOW_LAYERS_PER_LIGHT};
use crate::{
    LIGHT_DIRECTIONAL, LIGHT_POINT, MATERIAL_CONDUCTOR, MATERIAL_DIELECTRIC, MATERIAL_DIFFUSE, MATERIAL_MIRROR,
};

use super::RenderError;
use crate::shader_structs::{GpuLight, GpuMaterial, Vertex};

/// One indexed draw of one object.
#[derive(Clone, Copy, Debug)]
pub struct Draw {
    pub first_index: u32,
    pub index_count: u32,
    pub vertex_offset: i32,
    pub material: u32,
    /// The mesh is closed with outward normals ([`crate::scene::Mesh::is_closed_outward`]):
    /// seen from outside, its nearest surface is always a front face, so passes keeping
    /// the nearest surface may cull its back faces. Moves and uniform scaling keep it.
    pub closed: bool,
}

/// A shadow-map face to render: which atlas layer, and the light-space transform.
#[derive(Clone, Copy, Debug)]
pub struct ShadowFace {
    pub layer: u32,
    pub view_proj: Mat4,
    pub light: [f32; 4],
    pub origin: [f32; 4],
    /// The projection's near-plane distance from the light (0 for a directional light's box,
    /// which begins before the scene's bounding sphere).
    pub near: f32,
}

pub struct GpuScene {
    pub vertices: Buffer,
    /// The vertices as the exact tracer reads them: two RGBA32UI texels per [`Vertex`]
    /// (glsl/reference/trace.glsl), or why the device cannot (maxTexelBufferElements).
    vertex_texels: Result<BufferView, String>,
    pub indices: Buffer,
    pub draws: Vec<Draw>,
    pub materials: Buffer,
    pub environment: Image,
    pub environment_id: ImageId,
    pub env_sh: [[f32; 4]; 9],
    pub lights: Vec<GpuLight>,
    pub shadow_faces: Vec<ShadowFace>,
    /// Centre and radius of a sphere bounding every object and the camera.
    pub bounds_center: Vec3,
    pub bounds_radius: f32,
}

impl GpuScene {
    /// The vertices as the exact tracer reads them, or the device limit they exceed.
    pub fn vertex_texels(&self) -> GpuResult<&BufferView> {
        self.vertex_texels.as_ref().map_err(|why| GpuError::Unsupported(why.clone()))
    }
}

/// The vertices as uploaded: a scene without meshes (a volume alone) gets one unused vertex,
/// since the tracers' texel view of the buffer cannot be empty.
fn at_least_one(mut vertices: Vec<Vertex>) -> Vec<Vertex> {
    if vertices.is_empty() {
        vertices.push(Vertex::default());
    }
    vertices
}

fn v4(v: Vec3, w: f32) -> [f32; 4] {
    [v.x, v.y, v.z, w]
}

pub fn gpu_material(m: &Material) -> GpuMaterial {
    let kind = |k: u32| k as f32;
    match m {
        Material::Diffuse { albedo: Albedo::Constant(c) } => {
            GpuMaterial { albedo_a: v4(*c, kind(MATERIAL_DIFFUSE)), ..Default::default() }
        }
        Material::Diffuse { albedo: Albedo::Checker { a, b, size } } => {
            GpuMaterial { albedo_a: v4(*a, kind(MATERIAL_DIFFUSE)), albedo_b: v4(*b, *size), ..Default::default() }
        }
        Material::Mirror { reflectance } => GpuMaterial {
            albedo_a: v4(Vec3::ZERO, kind(MATERIAL_MIRROR)),
            spec_a: v4(*reflectance, 0.0),
            ..Default::default()
        },
        Material::Conductor { eta, k } => GpuMaterial {
            albedo_a: v4(Vec3::ZERO, kind(MATERIAL_CONDUCTOR)),
            spec_a: v4(*eta, 0.0),
            spec_b: v4(*k, 0.0),
            ..Default::default()
        },
        Material::Dielectric { ior, absorption } => GpuMaterial {
            albedo_a: v4(Vec3::ZERO, kind(MATERIAL_DIELECTRIC)),
            spec_a: v4(*ior, 0.0),
            spec_b: v4(*absorption, 0.0),
            ..Default::default()
        },
    }
}

/// The grid's SH coefficients, by the midpoint rule of [`environment_sh`] over the grid's
/// formula at GRID_SH_WIDTH x GRID_SH_WIDTH / 2 texel centres: 0.18 degree per texel, five
/// samples across a line. Computed once per process.
fn grid_sh() -> [[f32; 4]; 9] {
    static SH: std::sync::OnceLock<[[f32; 4]; 9]> = std::sync::OnceLock::new();
    *SH.get_or_init(|| {
        let (w, h) = (GRID_SH_WIDTH, GRID_SH_WIDTH / 2);
        environment_sh(w, h, &crate::scene::grid_texels(w, h))
    })
}

/// Width of the lat-long sampling of the grid that its irradiance is integrated from.
pub(crate) const GRID_SH_WIDTH: u32 = 2048;

/// Irradiance spherical-harmonic coefficients L_lm of a lat-long map (Ramamoorthi & Hanrahan
/// 2001, Eq. 10): sum of L(d) Y_lm(d) dOmega over texels, dOmega = (2pi/W)(pi/H) sin(theta).
pub fn environment_sh(width: u32, height: u32, texels: &[[f32; 4]]) -> [[f32; 4]; 9] {
    project_sh(width, height, texels, |d| Some((d, 1.0)))
}

/// The same coefficients for the environment as seen from under a flat interface y = const of
/// index `ior` (a water surface at rest): the sky's radiance L(d_a), d_a.y > 0, reaches the
/// water along the refracted direction d_w (Snell's window), scaled by the Fresnel
/// transmittance T and by ior^2 (SCENES.md's radiance scaling); below the horizon nothing
/// arrives through the surface (the directions under Snell's window see the pool by total
/// internal reflection, a second diffuse vertex). Integrated over the air's texels:
/// ior^2 dOmega_w = (cos_a / cos_w) dOmega_a, so the irradiance a receiver under the water gets
/// is E(n) of these coefficients (glsl/include/environment.glsl, `sh_irradiance`).
pub fn environment_sh_below(width: u32, height: u32, texels: &[[f32; 4]], ior: f32) -> [[f32; 4]; 9] {
    let ior = f64::from(ior.max(1e-6));
    project_sh(width, height, texels, |[x, y, z]| {
        if y <= 0.0 {
            return None;
        }
        let (wx, wz) = (x / ior, z / ior);
        let cos_w = (1.0 - wx * wx - wz * wz).sqrt();
        let t = 1.0 - fresnel_dielectric(y, 1.0 / ior);
        Some(([wx, cos_w, wz], t * y / cos_w))
    })
}

/// Exact unpolarised Fresnel reflectance for cos_i on the incident side, eta = n_i / n_t
/// (glsl/include/fresnel.glsl's `fresnel_dielectric`).
pub fn fresnel_dielectric(cos_i: f64, eta: f64) -> f64 {
    let sin_t2 = eta * eta * (1.0 - cos_i * cos_i);
    if sin_t2 >= 1.0 {
        return 1.0;
    }
    let cos_t = (1.0 - sin_t2).sqrt();
    let rs = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    let rp = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    0.5 * (rs * rs + rp * rp)
}

/// Samples per side, at least, of the midpoint rule in [`project_sh`] (lat-long, twice as many
/// in longitude): a map with fewer texels is sampled within its texels, each sample reading
/// the texel it falls in (the nearest lookup's piecewise-constant map). One sample per texel
/// of a 1x1 map, a constant environment, put its one sample on the horizon and gave a floor
/// 0.59 pi L and a wall facing -z 6.7 pi L instead of pi L; 256 x 128 samples integrate a
/// constant to within 1e-4 (tests below).
const SH_MIN_SAMPLES: usize = 128;

/// Sum over the lat-long map of L(d) Y_lm(d') w dOmega, where `f` maps a sample's direction
/// d to the direction d' its radiance is seen along and a weight w (None: not seen).
fn project_sh(
    width: u32,
    height: u32,
    texels: &[[f32; 4]],
    f: impl Fn([f64; 3]) -> Option<([f64; 3], f64)>,
) -> [[f32; 4]; 9] {
    let mut sh = [[0f64; 3]; 9];
    let (tw, th) = (width as usize, height as usize);
    let (w, h) = (tw.max(2 * SH_MIN_SAMPLES), th.max(SH_MIN_SAMPLES));
    for j in 0..h {
        let theta = (j as f64 + 0.5) / h as f64 * std::f64::consts::PI;
        let d_omega = (2.0 * std::f64::consts::PI / w as f64) * (std::f64::consts::PI / h as f64) * theta.sin();
        for i in 0..w {
            let u = (i as f64 + 0.5) / w as f64;
            // Inverse of u = 0.5 + atan2(x, -z) / (2 pi), v = acos(y) / pi.
            let phi = (u - 0.5) * 2.0 * std::f64::consts::PI;
            let Some(([x, y, z], weight)) = f([theta.sin() * phi.sin(), theta.cos(), -theta.sin() * phi.cos()]) else {
                continue;
            };
            let basis = [
                0.282095,
                0.488603 * y,
                0.488603 * z,
                0.488603 * x,
                1.092548 * x * y,
                1.092548 * y * z,
                0.315392 * (3.0 * z * z - 1.0),
                1.092548 * x * z,
                0.546274 * (x * x - y * y),
            ];
            let t = texels[j * th / h * tw + i * tw / w];
            for (k, b) in basis.iter().enumerate() {
                for c in 0..3 {
                    sh[k][c] += t[c] as f64 * b * weight * d_omega;
                }
            }
        }
    }
    sh.map(|c| [c[0] as f32, c[1] as f32, c[2] as f32, 0.0])
}

/// View matrices of the six cube faces, in Vulkan's cube-map face order (+X, -X, +Y, -Y,
/// +Z, -Z). The up vectors follow the cube-map addressing table of the Vulkan spec (16.5.4):
/// for +X, s = -z and t = -y, so "up" in the face's view is -Y. Used with a projection that
/// is *not* y-flipped, the rendered rows match the sampler's t axis.
pub fn cube_face_views(eye: Vec3) -> [Mat4; 6] {
    let f = |dir: Vec3, up: Vec3| Mat4::look_at_rh(eye, eye + dir, up);
    [
        f(Vec3::X, -Vec3::Y),
        f(-Vec3::X, -Vec3::Y),
        f(Vec3::Y, Vec3::Z),
        f(-Vec3::Y, -Vec3::Z),
        f(Vec3::Z, -Vec3::Y),
        f(-Vec3::Z, -Vec3::Y),
    ]
}

/// Every object's world-space mesh, concatenated: vertices, indices, one draw per object, and
/// the bounding sphere (centre, radius) of the objects and the camera.
fn geometry(scene: &Scene) -> (Vec<Vertex>, Vec<u32>, Vec<Draw>, Vec3, f32) {
    let mut vertices: Vec<Vertex> = Vec::new();
    let mut indices: Vec<u32> = Vec::new();
    let mut draws = Vec::new();
    let (mut lo, mut hi) = (scene.camera.position, scene.camera.position);
    for o in &scene.objects {
        let m = &o.mesh;
        draws.push(Draw {
            first_index: indices.len() as u32,
            index_count: m.indices.len() as u32,
            vertex_offset: vertices.len() as i32,
            material: o.material as u32,
            closed: m.is_closed_outward(),
        });
        for k in 0..m.positions.len() {
            let p = m.positions[k];
            lo = lo.min(p);
            hi = hi.max(p);
            vertices.push(Vertex {
                position: p.to_array(),
                normal: m.normals[k].to_array(),
                checker_uv: m.checker_uv.get(k).copied().unwrap_or_default().to_array(),
            });
        }
        indices.extend_from_slice(&m.indices);
    }
    let bounds_center = (lo + hi) * 0.5;
    let bounds_radius = ((hi - lo).length() * 0.5).max(1e-6);
    (vertices, indices, draws, bounds_center, bounds_radius)
}

/// The lights' uniforms and their shadow faces; each light owns SHADOW_LAYERS_PER_LIGHT atlas
/// layers.
fn lights(
    scene: &Scene,
    bounds_center: Vec3,
    bounds_radius: f32,
    shadow_size: u32,
) -> (Vec<GpuLight>, Vec<ShadowFace>) {
    let mut lights = Vec::new();
    let mut shadow_faces = Vec::new();
    let texel = 2.0 / shadow_size.max(1) as f32;
    for (i, l) in scene.lights.iter().enumerate() {
        let base = i as u32 * SHADOW_LAYERS_PER_LIGHT;
        match l {
            Light::Point { position, intensity } => {
                // Near/far bound every object from the light; near is small relative to
                // the scene so that tiny and huge scenes behave alike.
                let far = (position.distance(bounds_center) + bounds_radius) * 1.01;
                let near = (far * 1e-4).max(1e-9);
                let proj = Mat4::perspective_rh(std::f32::consts::FRAC_PI_2, 1.0, near, far);
                for (f, view) in cube_face_views(*position).iter().enumerate() {
                    shadow_faces.push(ShadowFace {
                        layer: base + f as u32,
                        view_proj: proj * *view,
                        light: v4(*position, LIGHT_POINT as f32),
                        origin: [0.0; 4],
                        near,
                    });
                }
                lights.push(GpuLight {
                    position: v4(*position, LIGHT_POINT as f32),
                    intensity: v4(*intensity, base as f32),
                    // A cube texel at distance r spans about 2r/size: offset by 1.5 texels.
                    shadow: [near, far, 1.5 * texel, 1.0 / shadow_size.max(1) as f32],
                    origin: [0.0; 4],
                    view_proj: Mat4::IDENTITY.to_cols_array_2d(),
                });
            }
            Light::Directional { direction, irradiance } => {
                let dir = direction.normalize();
                let r = bounds_radius * 1.01;
                let origin = bounds_center - dir * r;
                let up = if dir.y.abs() > 0.99 { Vec3::Z } else { Vec3::Y };
                let view = Mat4::look_at_rh(origin, origin + dir, up);
                let proj = Mat4::orthographic_rh(-r, r, -r, r, 0.0, 2.0 * r);
                let view_proj = proj * view;
                shadow_faces.push(ShadowFace {
                    layer: base,
                    view_proj,
                    light: v4(dir, LIGHT_DIRECTIONAL as f32),
                    origin: v4(origin, 0.0),
                    near: 0.0,
                });
                lights.push(GpuLight {
                    position: v4(dir, LIGHT_DIRECTIONAL as f32),
                    intensity: v4(*irradiance, base as f32),
                    // A texel spans 2r/size metres: offset by 1.5 texels.
                    shadow: [0.0, 2.0 * r, 1.5 * 2.0 * r / shadow_size.max(1) as f32, 1.0 / shadow_size.max(1) as f32],
                    origin: v4(origin, 0.0),
                    view_proj: view_proj.to_cols_array_2d(),
                });
            }
        }
    }
    (lights, shadow_faces)
}

impl GpuScene {
    pub fn new(
        ctx: &Arc<GpuContext>,
        scene: &Scene,
        graph: &mut FrameGraph,
        shadow_size: u32,
    ) -> Result<GpuScene, RenderError> {
        if scene.lights.len() > MAX_LIGHTS as usize {
            return Err(RenderError::Limit(format!(
                "the scene has {} lights; prism supports at most {MAX_LIGHTS} (MAX_LIGHTS in src/shader_shared.rs)",
                scene.lights.len()
            )));
        }
        let (vertices, indices, draws, bounds_center, bounds_radius) = geometry(scene);
        let vertices = at_least_one(vertices);
        // Host-visible buffers: written once here, read by the GPU after the submission that
        // follows (host writes are visible to every later queue submission).
        // Also storage buffers (the heightfield animation writes the vertices) and, for the
        // vertices, a texel buffer (the exact tracer reads them).
        let usage = |u: vk::BufferUsageFlags| u | vk::BufferUsageFlags::STORAGE_BUFFER;
        let vertex_usage = usage(vk::BufferUsageFlags::VERTEX_BUFFER | vk::BufferUsageFlags::UNIFORM_TEXEL_BUFFER);
        let vertices = Buffer::with_data(ctx, "scene_vertices", &vertices, vertex_usage)?;
        // A scene past the limit renders: only the tracers refuse it.
        let vertex_texels = match BufferView::new(ctx, &vertices, vk::Format::R32G32B32A32_UINT) {
            Err(GpuError::Unsupported(why)) => Err(why),
            view => Ok(view?),
        };
        let indices = Buffer::with_data(ctx, "scene_indices", &indices, usage(vk::BufferUsageFlags::INDEX_BUFFER))?;
        // The frame set binds the materials as a uniform buffer of MAX_MATERIALS entries
        // (glsl/include/frame.glsl), so it holds that many; ray tracers bind it as storage.
        let mut mats: Vec<GpuMaterial> = scene.materials.iter().map(gpu_material).collect();
        mats.resize(MAX_MATERIALS as usize, GpuMaterial::default());
        let material_usage = vk::BufferUsageFlags::UNIFORM_BUFFER | vk::BufferUsageFlags::STORAGE_BUFFER;
        let materials = Buffer::with_data(ctx, "scene_materials", &mats, material_usage)?;

        // Environment: always a texture (a constant is a 1x1 map, the grid a 1x1 map that
        // names it) so one lookup serves all (glsl/include/common.glsl).
        let (w, h, texels, env_sh) = match &scene.environment {
            Environment::Constant(c) => {
                let t = vec![[c.x, c.y, c.z, 1.0]];
                (1, 1, t.clone(), environment_sh(1, 1, &t))
            }
            Environment::Grid => (1, 1, vec![[0.0, 0.0, 0.0, ENVIRONMENT_GRID_ALPHA]], grid_sh()),
            Environment::Image { width, height, texels, .. } => {
                // Alpha 1 everywhere: the grid's alpha must not be read from a file.
                let t: Vec<[f32; 4]> = texels.iter().map(|&[r, g, b, _]| [r, g, b, 1.0]).collect();
                (*width, *height, t, environment_sh(*width, *height, texels))
            }
        };
        let max = ctx.limits().max_image_dimension2_d;
        if w > max || h > max {
            let file = match &scene.environment {
                Environment::Image { path, .. } => path.display().to_string(),
                Environment::Constant(_) | Environment::Grid => String::new(),
            };
            return Err(RenderError::Limit(format!(
                "environment.file {file} is {w}x{h} texels; the device's maxImageDimension2D is {max}: \
                 downscale the image to at most {max} texels on each side"
            )));
        }
        let environment = Image::new(
            ctx,
            &ImageDesc::d2(
                "environment",
                vk::Format::R32G32B32A32_SFLOAT,
                w,
                h,
                vk::ImageUsageFlags::SAMPLED | vk::ImageUsageFlags::TRANSFER_DST,
            ),
        )?;
        let environment_id = graph.register_image(&environment);
        let staging = Buffer::new(
            ctx,
            "environment_staging",
            (texels.len() * 16) as u64,
            vk::BufferUsageFlags::TRANSFER_SRC,
            MemoryLocation::CpuToGpu,
        )?;
        let mut staging = staging;
        staging.write(0, bytemuck::cast_slice(&texels));
        ctx.one_shot(|cmd| {
            graph.access_now(cmd, &[(environment_id, crate::gpu::Access::TransferWrite)], &[]);
            cmd.copy_buffer_to_image(&staging, &environment);
            graph.access_now(cmd, &[(environment_id, crate::gpu::Access::FragmentSampled)], &[]);
        })?;
        drop(staging);

        let (lights, shadow_faces) = lights(scene, bounds_center, bounds_radius, shadow_size);
        Ok(GpuScene {
            vertices,
            vertex_texels,
            indices,
            draws,
            materials,
            environment,
            environment_id,
            env_sh,
            lights,
            shadow_faces,
            bounds_center,
            bounds_radius,
        })
    }

    /// Objects and lights moved, or meshes changed shape with the same vertex and index
    /// counts (the water's heightfield over time): rewrite the vertices in place and derive
    /// the bounds, the lights and the shadow faces again. The caller waits for the GPU first
    /// and has checked that the topology is unchanged.
    pub fn update_placement(&mut self, scene: &Scene, shadow_size: u32) {
        let (vertices, _, _, center, radius) = geometry(scene);
        let vertices = at_least_one(vertices);
        let bytes: &[u8] = bytemuck::cast_slice(&vertices);
        assert_eq!(bytes.len(), self.vertices.read().len(), "update_placement with a changed topology");
        self.vertices.write(0, bytes);
        (self.bounds_center, self.bounds_radius) = (center, radius);
        (self.lights, self.shadow_faces) = lights(scene, center, radius, shadow_size);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A constant environment L has irradiance pi L for every normal: the SH projection
    /// must reproduce it (c4 L00 = 0.886227 * 0.282095 * 4 pi L = pi L), from the 1x1 map a
    /// constant environment is uploaded as, and from a larger map alike, for every normal. The
    /// midpoint rule in theta over 128 rows errs by about (pi / 128)^2 / 24 = 2.5e-5 of the
    /// integral.
    #[test]
    fn constant_environment_irradiance_is_pi_l() {
        for (w, h) in [(1, 1), (2, 1), (64, 32), (512, 256)] {
            let sh = environment_sh(w, h, &vec![[0.5, 1.0, 2.0, 1.0]; (w * h) as usize]);
            let l: Vec<f64> = sh.iter().map(|c| c[1] as f64).collect();
            let normals = [[1.0, 0.0, 0.0], [-1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, -1.0, 0.0], [0.0, 0.0, 1.0]];
            let diagonal = [0.577_350_3, 0.577_350_3, -0.577_350_3];
            for [x, y, z] in normals.into_iter().chain([[0.0, 0.0, -1.0], diagonal]) {
                // glsl/include/environment.glsl's sh_irradiance (Ramamoorthi & Hanrahan, Eq. 13).
                let (c1, c2, c3, c4, c5) = (0.429043, 0.511664, 0.743125, 0.886227, 0.247708);
                let e = c1 * l[8] * (x * x - y * y) + c3 * l[6] * z * z + c4 * l[0] - c5 * l[6]
                    + 2.0 * c1 * (l[4] * x * y + l[7] * x * z + l[5] * y * z)
                    + 2.0 * c2 * (l[3] * x + l[1] * y + l[2] * z);
                let pi = std::f64::consts::PI;
                assert!((e - pi).abs() < 1e-4 * pi, "{w}x{h}: E({x}, {y}, {z}) = {e}, not pi");
            }
        }
    }

    /// Every cube face's view must map its own axis to the centre of the face and agree with
    /// the Vulkan cube addressing table (s, t) for a direction off-centre.
    #[test]
    fn cube_faces_match_vulkan_addressing() {
        let views = cube_face_views(Vec3::ZERO);
        let proj = Mat4::perspective_rh(std::f32::consts::FRAC_PI_2, 1.0, 0.1, 10.0);
        // (major axis, s-axis direction, t-axis direction) from the spec's table.
        let table = [
            (Vec3::X, -Vec3::Z, -Vec3::Y),
            (-Vec3::X, Vec3::Z, -Vec3::Y),
            (Vec3::Y, Vec3::X, Vec3::Z),
            (-Vec3::Y, Vec3::X, -Vec3::Z),
            (Vec3::Z, Vec3::X, -Vec3::Y),
            (-Vec3::Z, -Vec3::X, -Vec3::Y),
        ];
        for (f, (major, s, t)) in table.iter().enumerate() {
            let d = *major + 0.3 * *s + 0.2 * *t;
            let clip = proj * views[f] * d.extend(1.0);
            let ndc = clip.truncate() / clip.w;
            assert!((ndc.x - 0.3).abs() < 1e-5 && (ndc.y - 0.2).abs() < 1e-5, "face {f}: {ndc:?}");
        }
    }
}
