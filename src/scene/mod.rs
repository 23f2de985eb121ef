//! Scenes: the TOML scene file, its `--set` overrides, and the validated, tessellated
//! [`Scene`] every pass and the reference renderer consume.
//!
//! The format and its conventions are documented key by key in docs/scene-format.md;
//! the benchmark scenes under assets/scenes/ follow ../shared/SCENES.md exactly.
//! Loading never panics on bad input: every mistake is a [`SceneError`] naming the
//! file, line and column and what to do.

mod environment;
mod error;
mod file;
pub mod fuzz;
mod mesh;
mod read;
mod shapes;
pub mod techniques;
mod volume;
pub mod volume_sources;

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

use glam::{Mat4, Quat, Vec2, Vec3};

pub use environment::{dir_to_latlong, grid_radiance, grid_texels, latlong_dir, Environment};
pub use error::{line_col, ErrorKind, Location, SceneError};
pub use mesh::{parse_obj, Mesh, ObjError};
pub use shapes::{wave_height, wave_normal, Wave};
pub use volume::{IndexProfile, Volume, MAX_VOLUME_RESOLUTION};

use file::{check_keys, list, FileObject, FileScene, Rgb, Source};

/// Accepted values of `render.refraction`; the first is the default. A technique
/// joins the benchmark by adding its name here (and to docs/scene-format.md).
pub const REFRACTION_TECHNIQUES: &[&str] = &["single", "wyman", "hu_qin", "impostor", "raytrace", "water"];
/// Accepted values of `render.reflection`; the first is the default.
pub const REFLECTION_TECHNIQUES: &[&str] = &["single", "impostor", "raytrace"];
/// Accepted values of `render.caustics`; the first is the default.
pub const CAUSTICS_TECHNIQUES: &[&str] = &["none", "caustics_map", "photon_buffer", "impostor_lightmap", "raytrace"];
/// Accepted values of `render.volume`, how a `[volume]` is rendered; the first is the default.
/// `eikonal`: Ihrke et al. 2007 (src/technique/eikonal); `raytrace`: the whole frame traced
/// exactly, the volume crossed as the reference crosses it (src/technique/raytrace.rs).
pub const VOLUME_TECHNIQUES: &[&str] = &["eikonal", "raytrace"];

/// Accepted values of `render.tonemap`; the first is the default (SCENES.md's PNG rule).
/// `adaptive`: Ihrke et al. 2007 §5.3 after Krawczyk et al. 2005 (src/technique/baseline/tonemap.rs).
pub const TONEMAPS: &[&str] = &["clamp", "adaptive"];

/// Accepted values of `render.update`; the first is the default. When what techniques keep
/// from frame to frame (shadow maps, impostor textures, caustic maps) is rendered: after a
/// change only, or every frame as in a fully dynamic scene (src/technique/mod.rs,
/// `Regeneration`).
pub const UPDATES: &[&str] = &["on_change", "every_frame"];

/// The technique keys of `[render]` and their accepted values.
pub const TECHNIQUE_KEYS: &[(&str, &[&str])] = &[
    ("refraction", REFRACTION_TECHNIQUES),
    ("reflection", REFLECTION_TECHNIQUES),
    ("caustics", CAUSTICS_TECHNIQUES),
    ("volume", VOLUME_TECHNIQUES),
    ("tonemap", TONEMAPS),
    ("update", UPDATES),
];

/// The baseline selection of every effect, as `--set` overrides: single-interface refraction,
/// classic environment-mapped reflection, no caustics (the defaults of `[render]`). Every
/// technique is timed and measured against it; the bundled scenes select better techniques,
/// so `prism report` and the tests start from this to measure what they name.
pub const BASELINE: &[&str] = &["render.refraction=single", "render.reflection=single", "render.caustics=none"];

/// Every `shape` an object may have.
pub const SHAPES: &[&str] = &["sphere", "quad", "box", "torus", "open_cylinder", "lathe", "heightfield", "mesh"];

/// `env!("CARGO_MANIFEST_DIR")/assets`.
pub fn assets_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("assets")
}

/// The scene used when none is named: assets/scenes/caustic_sphere.toml, whose techniques
/// show a glass ball refracting the floor above its caustic.
pub fn default_scene_path() -> PathBuf {
    benchmark_scene_path(DEFAULT_SCENE)
}

/// The name of the scene used when none is named.
pub const DEFAULT_SCENE: &str = "caustic_sphere";

/// The path of benchmark scene `name` (e.g. "sphere_env") under assets/scenes/.
pub fn benchmark_scene_path(name: &str) -> PathBuf {
    assets_dir().join("scenes").join(format!("{name}.toml"))
}

/// The names of the scenes bundled in assets/scenes/ (every `.toml` file there), sorted.
pub fn bundled_scenes() -> std::io::Result<Vec<String>> {
    let mut names = Vec::new();
    for entry in std::fs::read_dir(assets_dir().join("scenes"))? {
        let path = entry?.path();
        if path.extension().is_some_and(|e| e == "toml") {
            if let Some(stem) = path.file_stem() {
                names.push(stem.to_string_lossy().into_owned());
            }
        }
    }
    names.sort();
    Ok(names)
}

/// The benchmark scenes of SCENES.md, in its order.
pub const BENCHMARK_SCENES: &[&str] = &[
    "sphere_env",
    "bunny_env",
    "bubble_env",
    "sphere_nearby",
    "caustic_sphere",
    "caustic_bunny",
    "metal_ring",
    "water_pool",
    "room_mirror",
    "room_glass",
];

#[derive(Debug, Clone)]
pub struct Scene {
    /// The file's `name`, or its file stem.
    pub name: String,
    /// The file's `description`: one line saying what the scene shows.
    pub description: Option<String>,
    /// The scene file (or the `origin` given to [`load_str`]).
    pub source: PathBuf,
    pub camera: Camera,
    pub environment: Environment,
    pub lights: Vec<Light>,
    /// Indexed by [`Object::material`]; sorted by name.
    pub materials: Vec<Material>,
    /// `materials[i]` is `[materials.<material_names[i]>]`.
    pub material_names: Vec<String>,
    pub objects: Vec<Object>,
    /// The `[volume]` table: an inhomogeneous refractive volume (eikonal rendering).
    pub volume: Option<Volume>,
    pub render: RenderSettings,
    /// The effective scene after overrides as normalized TOML (keys sorted, comments
    /// dropped): equal scenes give equal strings, for hashing, caching and metadata.
    pub canonical: String,
}

impl Scene {
    pub fn material_of(&self, object: &Object) -> &Material {
        &self.materials[object.material]
    }

    pub fn material_index(&self, name: &str) -> Option<usize> {
        self.material_names.iter().position(|n| n == name)
    }

    pub fn object(&self, name: &str) -> Option<&Object> {
        self.objects.iter().find(|o| o.name == name)
    }
}

/// A pinhole camera.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Camera {
    pub position: Vec3,
    pub target: Vec3,
    pub up: Vec3,
    /// Vertical field of view, degrees.
    pub vfov_deg: f32,
    pub width: u32,
    pub height: u32,
}

impl Camera {
    /// World -> view (right-handed, looking down -Z).
    pub fn view(&self) -> Mat4 {
        Mat4::look_at_rh(self.position, self.target, self.up)
    }

    pub fn aspect(&self) -> f32 {
        self.width as f32 / self.height as f32
    }

    /// The ray (origin, unit direction) through the centre of pixel (i, j):
    /// ((i + 0.5) / W, (j + 0.5) / H) of the image, j = 0 the top row.
    pub fn primary_ray(&self, i: u32, j: u32) -> (Vec3, Vec3) {
        self.ray_through(i as f32 + 0.5, j as f32 + 0.5)
    }

    /// The ray (origin, unit direction) through image point (x, y) in pixels, (0, 0) the
    /// top-left corner of the image.
    pub fn ray_through(&self, x: f32, y: f32) -> (Vec3, Vec3) {
        let forward = (self.target - self.position).normalize();
        let right = forward.cross(self.up).normalize();
        let up = right.cross(forward);
        let tan_half = (self.vfov_deg.to_radians() * 0.5).tan();
        let u = (2.0 * x / self.width as f32 - 1.0) * tan_half * self.aspect();
        let v = (1.0 - 2.0 * y / self.height as f32) * tan_half;
        (self.position, (forward + u * right + v * up).normalize())
    }
}

#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Light {
    /// Intensity in W/sr per channel.
    Point { position: Vec3, intensity: Vec3 },
    /// `direction` is unit length, pointing from the light into the scene; irradiance
    /// in W/m^2 on a surface facing the light.
    Directional { direction: Vec3, irradiance: Vec3 },
}

/// Equal in red, green and blue.
pub fn is_grey(c: Vec3) -> bool {
    c.x == c.y && c.y == c.z
}

impl Light {
    /// Whether it sends the same power in red, green and blue.
    pub fn is_grey(&self) -> bool {
        match self {
            Light::Point { intensity, .. } => is_grey(*intensity),
            Light::Directional { irradiance, .. } => is_grey(*irradiance),
        }
    }
}

#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Material {
    Diffuse {
        albedo: Albedo,
    },
    Mirror {
        reflectance: Vec3,
    },
    /// Complex index of refraction eta + i k per channel, for Fresnel on metals.
    Conductor {
        eta: Vec3,
        k: Vec3,
    },
    /// `ior` per channel (equal channels: no dispersion); Beer-Lambert `absorption`
    /// per metre.
    Dielectric {
        ior: Vec3,
        absorption: Vec3,
    },
}

impl Material {
    pub fn is_specular(&self) -> bool {
        !self.is_diffuse()
    }

    pub fn is_diffuse(&self) -> bool {
        matches!(self, Material::Diffuse { .. })
    }

    pub fn kind_name(&self) -> &'static str {
        match self {
            Material::Diffuse { .. } => "diffuse",
            Material::Mirror { .. } => "mirror",
            Material::Conductor { .. } => "conductor",
            Material::Dielectric { .. } => "dielectric",
        }
    }
}

#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Albedo {
    Constant(Vec3),
    /// Squares of `size` metres: `a` where floor(s/size) + floor(t/size) is even.
    Checker {
        a: Vec3,
        b: Vec3,
        size: f32,
    },
}

impl Albedo {
    /// The albedo at checker coordinates `st` (see [`Mesh::checker_uv`]).
    pub fn eval(&self, st: Vec2) -> Vec3 {
        match *self {
            Albedo::Constant(c) => c,
            Albedo::Checker { a, b, size } => {
                let k = (st.x / size).floor() as i64 + (st.y / size).floor() as i64;
                if k.rem_euclid(2) == 0 {
                    a
                } else {
                    b
                }
            }
        }
    }
}

#[derive(Debug, Clone)]
pub struct Object {
    pub name: String,
    /// Index into [`Scene::materials`].
    pub material: usize,
    /// One of [`SHAPES`].
    pub shape: &'static str,
    /// World space.
    pub mesh: Mesh,
    /// The exact shape, where the reference renderer should not use the tessellation.
    pub analytic: Option<Analytic>,
    /// A heightfield's surface without its time, which the window animates on the GPU.
    pub heightfield: Option<shapes::Heightfield>,
}

#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Analytic {
    Sphere { center: Vec3, radius: f32 },
}

#[derive(Debug, Clone, PartialEq)]
pub struct RenderSettings {
    pub refraction: String,
    pub reflection: String,
    pub caustics: String,
    /// One of [`VOLUME_TECHNIQUES`]: how a `[volume]` is rendered.
    pub volume: String,
    pub shadow_map_size: u32,
    pub exposure: f32,
    /// One of [`TONEMAPS`]: how PNG output (and the window) maps radiance to 8 bits.
    pub tonemap: String,
    /// Whether the scene file or a `--set` named `render.tonemap` (the demo window picks the
    /// adaptive tone map for volume scenes only when it was not named).
    pub tonemap_named: bool,
    /// Longitude segments of tessellated spheres (latitude: half).
    pub sphere_segments: u32,
    /// One of [`UPDATES`]: `every_frame` renders every kept result in every frame.
    pub update: String,
    /// Technique parameter tables, `[render.<name>]`, validated by the technique.
    pub params: BTreeMap<String, toml::Table>,
}

impl Default for RenderSettings {
    fn default() -> Self {
        RenderSettings {
            refraction: REFRACTION_TECHNIQUES[0].to_string(),
            reflection: REFLECTION_TECHNIQUES[0].to_string(),
            caustics: CAUSTICS_TECHNIQUES[0].to_string(),
            volume: VOLUME_TECHNIQUES[0].to_string(),
            shadow_map_size: 1024,
            exposure: 1.0,
            tonemap: TONEMAPS[0].to_string(),
            tonemap_named: false,
            sphere_segments: 128,
            update: UPDATES[0].to_string(),
            params: BTreeMap::new(),
        }
    }
}

/// Loads the scene file at `path`, applying `overrides` ("dotted.key=value").
pub fn load(path: &Path, overrides: &[String]) -> Result<Scene, SceneError> {
    let text = read::read_text(path, read::MAX_SCENE_BYTES)
        .map_err(|source| SceneError::Io { path: path.to_path_buf(), source })?;
    load_str(&text, path, overrides)
}

/// Loads a scene from `text`; `origin` is the file it stands for: relative paths are
/// resolved against its directory and errors name it.
pub fn load_str(text: &str, origin: &Path, overrides: &[String]) -> Result<Scene, SceneError> {
    let (file, src) = file::parse(text, origin, overrides)?;
    build(file, &src)
}

fn build(f: FileScene, src: &Source) -> Result<Scene, SceneError> {
    let render = render_settings(f.render.as_ref(), src)?;
    let camera = camera(&f.camera, src)?;
    let environment = environment(f.environment.as_ref(), src)?;
    let lights = f
        .lights
        .iter()
        .enumerate()
        .map(|(i, l)| light(l, &format!("lights.{i}"), src))
        .collect::<Result<Vec<_>, _>>()?;
    // Materials are indexed in sorted name order: the error points at the first beyond the limit.
    if let Some(extra) = f.materials.keys().nth(crate::MAX_MATERIALS as usize) {
        return Err(value_err(
            src,
            &format!("materials.{extra}"),
            format!("the scene defines {} materials; the limit is {}", f.materials.len(), crate::MAX_MATERIALS),
            "give objects with the same parameters one material, or split the scene",
        ));
    }
    let mut materials = Vec::new();
    let mut material_names = Vec::new();
    for (name, m) in &f.materials {
        materials.push(material(m, &format!("materials.{name}"), src)?);
        material_names.push(name.clone());
    }
    check_count(src, "objects", f.objects.len(), MAX_OBJECTS)?;
    check_tessellation(&f.objects, &render, src)?;
    let objects = f
        .objects
        .iter()
        .enumerate()
        .map(|(i, o)| object(o, i, &material_names, &render, src))
        .collect::<Result<Vec<_>, _>>()?;
    let volume = f.volume.as_ref().map(|v| volume::volume(v, src)).transpose()?;
    let name = f.name.clone().unwrap_or_else(|| {
        src.file.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_else(|| "scene".to_string())
    });
    if f.description.as_deref().is_some_and(|d| d.contains('\n')) {
        return Err(value_err(
            src,
            "description",
            "`description` spans several lines".into(),
            "write one line: it is what `prism scenes` prints",
        ));
    }
    Ok(Scene {
        name,
        description: f.description.clone(),
        source: src.file.clone(),
        camera,
        environment,
        lights,
        materials,
        material_names,
        objects,
        volume,
        render,
        canonical: file::canonical(src),
    })
}

// ---- value checks: each names the dotted path it checks, for file:line:col ----

fn value_err(src: &Source, path: &str, message: String, hint: &str) -> SceneError {
    src.error(ErrorKind::Value, path, message, hint.to_string())
}

/// `v` if `finite`, else the error naming `path`.
fn checked_finite<T: std::fmt::Display>(src: &Source, path: &str, v: T, finite: bool) -> Result<T, SceneError> {
    if !finite {
        return Err(value_err(
            src,
            path,
            format!("`{}` must be finite, not {v}", leaf(path)),
            "replace nan/inf with a number",
        ));
    }
    Ok(v)
}

fn vec3(src: &Source, path: &str, v: [f32; 3]) -> Result<Vec3, SceneError> {
    let v = Vec3::from(v);
    checked_finite(src, path, v, v.is_finite())
}

fn unit(src: &Source, path: &str, v: [f32; 3]) -> Result<Vec3, SceneError> {
    vec3(src, path, v)?.try_normalize().ok_or_else(|| {
        value_err(
            src,
            path,
            format!("`{}` has zero length", leaf(path)),
            "give a non-zero direction (it is normalized on load)",
        )
    })
}

fn finite(src: &Source, path: &str, v: f32) -> Result<f32, SceneError> {
    checked_finite(src, path, v, v.is_finite())
}

/// The magnitudes a length, size, scale or coordinate may have (where non-zero). Scenes
/// are rendered correctly from 1e-3 to 1e4 metres (tests/stability.rs); this leaves room
/// on both sides while refusing values whose squares or products leave f32's range.
pub const SCALE_RANGE: (f32, f32) = (1e-6, 1e6);

/// The open range of `camera.vfov_deg`, in degrees.
pub const VFOV_RANGE: (f32, f32) = (0.01, 179.0);

fn out_of_range(src: &Source, path: &str, what: &str, v: f32) -> SceneError {
    let (lo, hi) = SCALE_RANGE;
    value_err(
        src,
        path,
        format!("`{}` {what} from {lo:e} to {hi:e}, not {v:e}", leaf(path)),
        "scene lengths are in metres; scale the whole scene into range",
    )
}

/// A length, size, scale or exposure: greater than 0 and within [`SCALE_RANGE`].
// `!(v > 0.0)` rather than `v <= 0.0`: it also rejects NaN.
#[allow(clippy::neg_cmp_op_on_partial_ord)]
fn positive(src: &Source, path: &str, v: f32) -> Result<f32, SceneError> {
    if !(finite(src, path, v)? > 0.0) {
        return Err(value_err(
            src,
            path,
            format!("`{}` must be greater than 0, not {v}", leaf(path)),
            "use a positive number (lengths are in metres)",
        ));
    }
    if !(SCALE_RANGE.0..=SCALE_RANGE.1).contains(&v) {
        return Err(out_of_range(src, path, "must be", v));
    }
    Ok(v)
}

/// Most `[[objects]]` in a scene.
pub const MAX_OBJECTS: usize = 1024;
/// Most points in a lathe profile (an object's or a volume region's).
pub const MAX_PROFILE_POINTS: usize = 4096;
/// Most triangles the tessellated shapes (spheres, tori, cylinders, lathes, heightfields) of
/// a scene have together: one sphere at the largest `sphere_segments`, 8192.
pub const MAX_TESSELLATED_TRIANGLES: u64 = 1 << 26;
/// The triangle budget `check_tessellation` applies: [`MAX_TESSELLATED_TRIANGLES`], except
/// in a process that runs the fuzz bodies ([`fuzz`]), which lower it to
/// [`fuzz::TESSELLATED_TRIANGLES`] so that a legitimately large scene loads in
/// milliseconds and is not taken for a hang. The check itself is the same code.
static TESSELLATION_BUDGET: AtomicU64 = AtomicU64::new(MAX_TESSELLATED_TRIANGLES);
/// Most `waves` of a heightfield: h(x, z) is a sum over them at every vertex, on load and
/// on every animated frame (glsl/common/heightfield.comp); 64 sines already make a dense
/// ocean spectrum (water_pool uses two).
pub const MAX_WAVES: usize = 64;

/// Cells (nx, nz) of a heightfield without `resolution`.
const DEFAULT_HEIGHTFIELD_RESOLUTION: [u32; 2] = [128, 128];

/// Refuses the array at `path` when it has more than `max` entries, naming the first extra.
fn check_count(src: &Source, path: &str, n: usize, max: usize) -> Result<(), SceneError> {
    if n <= max {
        return Ok(());
    }
    Err(value_err(
        src,
        &format!("{path}.{max}"),
        format!("`{path}` has {n} entries; the limit is {max}"),
        "split the scene or use fewer entries",
    ))
}

/// Refuses a scene whose tessellated shapes would have more than
/// [`MAX_TESSELLATED_TRIANGLES`] triangles, before any is built.
fn check_tessellation(objects: &[FileObject], render: &RenderSettings, src: &Source) -> Result<(), SceneError> {
    let mut total = 0u64;
    for (i, o) in objects.iter().enumerate() {
        let s = u64::from(o.segments.unwrap_or(render.sphere_segments));
        let triangles = match o.shape.as_str() {
            "sphere" | "torus" => s * s,
            "open_cylinder" => 2 * s,
            "lathe" => 2 * s * o.profile.as_ref().map_or(0, |p| p.len() as u64),
            // Two per cell; each axis is at most 2^32 - 1, so the product fits in a u64 and
            // only the doubling can overflow.
            "heightfield" => {
                let [nx, nz] = o.resolution.unwrap_or(DEFAULT_HEIGHTFIELD_RESOLUTION).map(u64::from);
                (nx * nz).saturating_mul(2)
            }
            _ => 0,
        };
        total = total.saturating_add(triangles);
        let max = TESSELLATION_BUDGET.load(Ordering::Relaxed);
        if total > max {
            let key = if o.shape == "heightfield" {
                format!("objects.{i}.resolution")
            } else if o.segments.is_some() {
                format!("objects.{i}.segments")
            } else {
                "render.sphere_segments".into()
            };
            return Err(value_err(
                src,
                &key,
                format!(
                    "the tessellated shapes up to objects.{i} have {total} triangles; the limit is {max}"
                ),
                "lower `sphere_segments` (or an object's `segments`, or a heightfield's `resolution`) or use fewer curved objects",
            ));
        }
    }
    Ok(())
}

/// A point or offset in metres: each coordinate 0 or within [`SCALE_RANGE`] in magnitude.
fn point(src: &Source, path: &str, v: [f32; 3]) -> Result<Vec3, SceneError> {
    let v = vec3(src, path, v)?;
    let (lo, hi) = SCALE_RANGE;
    if let Some(c) = v.to_array().into_iter().find(|c| *c != 0.0 && !(lo..=hi).contains(&c.abs())) {
        return Err(out_of_range(src, path, "coordinates must be 0 or in magnitude", c));
    }
    Ok(v)
}

/// A colour or coefficient: finite and >= 0 (> 0 if `strict`) in every channel.
fn rgb(src: &Source, path: &str, c: Rgb, strict: bool) -> Result<Vec3, SceneError> {
    let v = vec3(src, path, c.0)?;
    let ok = if strict { v.cmpgt(Vec3::ZERO).all() } else { v.cmpge(Vec3::ZERO).all() };
    if !ok {
        let bound = if strict { "greater than 0" } else { "at least 0" };
        return Err(value_err(
            src,
            path,
            format!("`{}` must be {bound} in every channel, not {v}", leaf(path)),
            "give a scalar or [r, g, b] in range",
        ));
    }
    Ok(v)
}

/// The `transform` of the object or region at `path`: scale, then rotation (degrees about X,
/// then Y, then Z), then translation, applied to the shape's own coordinates (centre
/// included). Returns the matrix, its rotation and its scale.
fn transform(src: &Source, path: &str, t: Option<&file::FileTransform>) -> Result<(Mat4, Quat, f32), SceneError> {
    let p = |k: &str| format!("{path}.transform.{k}");
    let translation = point(src, &p("translation"), t.and_then(|t| t.translation).unwrap_or_default())?;
    let rot_deg = vec3(src, &p("rotation"), t.and_then(|t| t.rotation).unwrap_or_default())?;
    let scale = positive(src, &p("scale"), t.and_then(|t| t.scale).unwrap_or(1.0))?;
    let rotation = Quat::from_rotation_z(rot_deg.z.to_radians())
        * Quat::from_rotation_y(rot_deg.y.to_radians())
        * Quat::from_rotation_x(rot_deg.x.to_radians());
    Ok((Mat4::from_scale_rotation_translation(Vec3::splat(scale), rotation, translation), rotation, scale))
}

fn leaf(path: &str) -> &str {
    path.rsplit('.').next().unwrap_or(path)
}

fn render_settings(t: Option<&toml::Table>, src: &Source) -> Result<RenderSettings, SceneError> {
    let mut r = RenderSettings::default();
    let Some(t) = t else {
        return Ok(r);
    };
    const KEYS: &[&str] = &[
        "refraction",
        "reflection",
        "caustics",
        "volume",
        "tonemap",
        "update",
        "shadow_map_size",
        "exposure",
        "sphere_segments",
    ];
    let int = |key: &str, v: &toml::Value, lo: i64, hi: i64| -> Result<u32, SceneError> {
        let path = format!("render.{key}");
        match v.as_integer() {
            Some(n) if (lo..=hi).contains(&n) => Ok(n as u32),
            Some(n) => Err(value_err(
                src,
                &path,
                format!("`{key}` must be from {lo} to {hi}, not {n}"),
                "use an integer in range",
            )),
            None => Err(src.error(
                ErrorKind::Schema,
                &path,
                format!("`{key}` must be an integer, not a {}", v.type_str()),
                "write a whole number without quotes".to_string(),
            )),
        }
    };
    for (key, v) in t {
        let path = format!("render.{key}");
        if let Some((_, accepted)) = TECHNIQUE_KEYS.iter().find(|(k, _)| k == key) {
            let name = v.as_str().ok_or_else(|| {
                src.error(
                    ErrorKind::Schema,
                    &path,
                    format!("`{key}` must be a technique name (a string)"),
                    format!("accepted: {}", list(accepted)),
                )
            })?;
            if !accepted.contains(&name) {
                return Err(value_err(
                    src,
                    &path,
                    format!("unknown {key} technique `{name}`"),
                    &format!("accepted values: {}", list(accepted)),
                ));
            }
            match key.as_str() {
                "refraction" => r.refraction = name.to_string(),
                "reflection" => r.reflection = name.to_string(),
                "tonemap" => {
                    r.tonemap = name.to_string();
                    r.tonemap_named = true;
                }
                "update" => r.update = name.to_string(),
                "volume" => r.volume = name.to_string(),
                _ => r.caustics = name.to_string(),
            }
            continue;
        }
        match key.as_str() {
            "shadow_map_size" => r.shadow_map_size = int(key, v, 1, 16384)?,
            "sphere_segments" => r.sphere_segments = int(key, v, 3, 8192)?,
            "exposure" => {
                let e = v.as_float().or_else(|| v.as_integer().map(|i| i as f64));
                let e = e.ok_or_else(|| {
                    src.error(
                        ErrorKind::Schema,
                        &path,
                        "`exposure` must be a number".to_string(),
                        "write e.g. `exposure = 1.0`".to_string(),
                    )
                })?;
                r.exposure = positive(src, &path, e as f32)?;
            }
            _ => match v.as_table() {
                Some(table) if !techniques::TABLES.contains(&key.as_str()) => {
                    let mut hint = format!(
                        "the technique parameter tables are {}",
                        techniques::TABLES.iter().map(|t| format!("[render.{t}]")).collect::<Vec<_>>().join(", ")
                    );
                    if let Some(c) = techniques::closest(key, techniques::TABLES) {
                        hint = format!("did you mean [render.{c}]? {hint}");
                    }
                    // Point at the table's first key: in a file that is the table's first
                    // line, and from the command line the `--set` that created the table.
                    let at = table.keys().next().map_or(path.clone(), |k| format!("{path}.{k}"));
                    return Err(src.key_error(
                        ErrorKind::Schema,
                        &at,
                        format!("unknown technique table [render.{key}]"),
                        hint,
                    ));
                }
                // Technique parameters; the technique checks them.
                Some(p) => {
                    techniques::check(key, p).map_err(|e| {
                        value_err(
                            src,
                            &format!("render.{key}.{}", e.key),
                            format!("render.{key}: {}", e.message),
                            &e.hint,
                        )
                    })?;
                    r.params.insert(key.clone(), p.clone());
                }
                None => {
                    let mut hint =
                        format!("[render] takes {} and technique parameter tables [render.<technique>]", list(KEYS));
                    if let Some(c) = techniques::closest(key, KEYS) {
                        hint = format!("did you mean `{c}`? {hint}");
                    }
                    return Err(src.key_error(
                        ErrorKind::Schema,
                        &path,
                        format!("unknown key `{key}` in [render]"),
                        hint,
                    ));
                }
            },
        }
    }
    Ok(r)
}

fn camera(c: &file::FileCamera, src: &Source) -> Result<Camera, SceneError> {
    let position = point(src, "camera.position", c.position)?;
    let target = point(src, "camera.target", c.target)?;
    let up = unit(src, "camera.up", c.up.unwrap_or([0.0, 1.0, 0.0]))?;
    let vfov_deg = finite(src, "camera.vfov_deg", c.vfov_deg.unwrap_or(40.0))?;
    if !(vfov_deg >= VFOV_RANGE.0 && vfov_deg <= VFOV_RANGE.1) {
        return Err(value_err(
            src,
            "camera.vfov_deg",
            format!("`vfov_deg` must be from {} to {} degrees, not {vfov_deg}", VFOV_RANGE.0, VFOV_RANGE.1),
            "the vertical field of view is in degrees, e.g. 40",
        ));
    }
    let width = c.width.unwrap_or(512);
    let height = c.height.unwrap_or(512);
    for (key, v) in [("width", width), ("height", height)] {
        if v == 0 || v > 16384 {
            return Err(value_err(
                src,
                &format!("camera.{key}"),
                format!("`{key}` must be from 1 to 16384 pixels, not {v}"),
                "the image size is in pixels, e.g. 512",
            ));
        }
    }
    let forward = target - position;
    if forward.length() < 1e-6 {
        return Err(value_err(
            src,
            "camera.target",
            "`target` equals `position`, so the camera looks nowhere".to_string(),
            "move the target away from the camera position",
        ));
    }
    if forward.normalize().cross(up).length() < 1e-4 {
        return Err(value_err(
            src,
            "camera.up",
            "`up` is parallel to the viewing direction".to_string(),
            "choose an `up` not along target - position",
        ));
    }
    Ok(Camera { position, target, up, vfov_deg, width, height })
}

fn environment(e: Option<&file::FileEnvironment>, src: &Source) -> Result<Environment, SceneError> {
    let Some(e) = e else {
        return Ok(Environment::Grid);
    };
    let what = format!("environment type `{}`", e.kind);
    match e.kind.as_str() {
        "grid" => {
            check_keys(src, "environment", &what, &e.present(), &[], &[])?;
            Ok(Environment::Grid)
        }
        "constant" => {
            check_keys(src, "environment", &what, &e.present(), &["radiance"], &["radiance"])?;
            let radiance = e.radiance.unwrap_or(Rgb([0.0; 3]));
            Ok(Environment::Constant(rgb(src, "environment.radiance", radiance, false)?))
        }
        "image" => {
            check_keys(src, "environment", &what, &e.present(), &["file"], &["file"])?;
            let rel = e.file.as_deref().unwrap_or_default();
            let path = relative_to(&src.file, rel);
            let (width, height, texels) = environment::read_image(&path).map_err(|message| {
                let kind = if path.exists() { ErrorKind::Image } else { ErrorKind::MissingFile };
                src.error(
                    kind,
                    "environment.file",
                    format!("cannot load environment image {}: {message}", path.display()),
                    "give an .exr, .hdr or .png path relative to the scene file".to_string(),
                )
            })?;
            if width == 0 || height == 0 {
                return Err(src.error(
                    ErrorKind::Image,
                    "environment.file",
                    format!("environment image {} is empty", path.display()),
                    "use an image of at least 1 x 1 texels".to_string(),
                ));
            }
            Ok(Environment::Image { path, width, height, texels })
        }
        other => Err(value_err(
            src,
            "environment.type",
            format!("unknown environment type `{other}`"),
            "accepted values: `grid`, `constant`, `image`",
        )),
    }
}

/// `rel` resolved against the directory of scene file `scene`.
fn relative_to(scene: &Path, rel: &str) -> PathBuf {
    scene.parent().map(|d| d.join(rel)).unwrap_or_else(|| PathBuf::from(rel))
}

fn light(l: &file::FileLight, path: &str, src: &Source) -> Result<Light, SceneError> {
    let what = format!("light type `{}`", l.kind);
    match l.kind.as_str() {
        "point" => {
            let keys = ["position", "intensity"];
            check_keys(src, path, &what, &l.present(), &keys, &keys)?;
            Ok(Light::Point {
                position: point(src, &format!("{path}.position"), l.position.unwrap_or_default())?,
                intensity: rgb(src, &format!("{path}.intensity"), l.intensity.unwrap_or(Rgb([0.0; 3])), false)?,
            })
        }
        "directional" => {
            let keys = ["direction", "irradiance"];
            check_keys(src, path, &what, &l.present(), &keys, &keys)?;
            Ok(Light::Directional {
                direction: unit(src, &format!("{path}.direction"), l.direction.unwrap_or_default())?,
                irradiance: rgb(src, &format!("{path}.irradiance"), l.irradiance.unwrap_or(Rgb([0.0; 3])), false)?,
            })
        }
        other => Err(value_err(
            src,
            &format!("{path}.type"),
            format!("unknown light type `{other}`"),
            "accepted values: `point`, `directional`",
        )),
    }
}

fn material(m: &file::FileMaterial, path: &str, src: &Source) -> Result<Material, SceneError> {
    let what = format!("material type `{}`", m.kind);
    let p = |k: &str| format!("{path}.{k}");
    let zero = Rgb([0.0; 3]);
    match m.kind.as_str() {
        "diffuse" => {
            check_keys(src, path, &what, &m.present(), &["albedo", "checker"], &[])?;
            let albedo = match (m.albedo, &m.checker) {
                (Some(a), None) => Albedo::Constant(rgb(src, &p("albedo"), a, false)?),
                (None, Some(c)) => Albedo::Checker {
                    a: rgb(src, &p("checker.a"), c.a, false)?,
                    b: rgb(src, &p("checker.b"), c.b, false)?,
                    size: positive(src, &p("checker.size"), c.size)?,
                },
                (Some(_), Some(_)) => {
                    return Err(src.error(
                        ErrorKind::Schema,
                        path,
                        "a diffuse material takes `albedo` or `checker`, not both".to_string(),
                        "remove one of them".to_string(),
                    ))
                }
                (None, None) => {
                    return Err(src.error(
                        ErrorKind::Schema,
                        path,
                        "a diffuse material needs `albedo` or `checker`".to_string(),
                        "add e.g. `albedo = 0.8` or `checker = { a = 0.8, b = 0.2, size = 0.5 }`".to_string(),
                    ))
                }
            };
            Ok(Material::Diffuse { albedo })
        }
        "mirror" => {
            check_keys(src, path, &what, &m.present(), &["reflectance"], &["reflectance"])?;
            Ok(Material::Mirror { reflectance: rgb(src, &p("reflectance"), m.reflectance.unwrap_or(zero), false)? })
        }
        "conductor" => {
            check_keys(src, path, &what, &m.present(), &["eta", "k"], &["eta", "k"])?;
            Ok(Material::Conductor {
                eta: rgb(src, &p("eta"), m.eta.unwrap_or(zero), true)?,
                k: rgb(src, &p("k"), m.k.unwrap_or(zero), false)?,
            })
        }
        "dielectric" => {
            check_keys(src, path, &what, &m.present(), &["ior", "absorption"], &["ior"])?;
            Ok(Material::Dielectric {
                ior: rgb(src, &p("ior"), m.ior.unwrap_or(zero), true)?,
                absorption: rgb(src, &p("absorption"), m.absorption.unwrap_or(zero), false)?,
            })
        }
        other => Err(value_err(
            src,
            &p("type"),
            format!("unknown material type `{other}`"),
            "accepted values: `diffuse`, `mirror`, `conductor`, `dielectric`",
        )),
    }
}

/// Keys each shape takes besides name, material, shape and transform.
fn shape_keys(shape: &str) -> Option<(&'static [&'static str], &'static [&'static str])> {
    Some(match shape {
        "sphere" => (&["center", "radius", "segments"], &["radius"]),
        "quad" => (&["center", "size", "normal"], &["size", "normal"]),
        "box" => (&["center", "size"], &["size"]),
        "torus" => (&["center", "major_radius", "minor_radius", "segments"], &["major_radius", "minor_radius"]),
        "open_cylinder" => (&["center", "radius", "height", "segments"], &["radius", "height"]),
        "lathe" => (&["center", "profile", "segments"], &["profile"]),
        "heightfield" => (&["center", "size", "resolution", "waves", "time"], &["size"]),
        "mesh" => (&["file", "fit"], &["file"]),
        _ => return None,
    })
}

fn object(
    o: &FileObject,
    i: usize,
    material_names: &[String],
    render: &RenderSettings,
    src: &Source,
) -> Result<Object, SceneError> {
    let path = format!("objects.{i}");
    let p = |k: &str| format!("{path}.{k}");
    let shape: &'static str = SHAPES.iter().find(|s| **s == o.shape).copied().ok_or_else(|| {
        value_err(
            src,
            &p("shape"),
            format!("unknown shape `{}`", o.shape),
            &format!("accepted values: {}", list(SHAPES)),
        )
    })?;
    let material = material_names.iter().position(|n| *n == o.material).ok_or_else(|| {
        let names: Vec<&str> = material_names.iter().map(String::as_str).collect();
        src.error(
            ErrorKind::Reference,
            &p("material"),
            format!("unknown material `{}`", o.material),
            if names.is_empty() {
                format!("define it as [materials.{}]", o.material)
            } else {
                format!("known materials: {}; or define [materials.{}]", list(&names), o.material)
            },
        )
    })?;
    let (allowed, required) = shape_keys(shape).unwrap_or((&[], &[]));
    check_keys(src, &path, &format!("shape `{shape}`"), &o.present(), allowed, required)?;

    let (matrix, rotation, scale) = transform(src, &path, o.transform.as_ref())?;

    let center = point(src, &p("center"), o.center.unwrap_or_default())?;
    let segments = o.segments.unwrap_or(render.sphere_segments);
    if o.segments.is_some() && !(3..=8192).contains(&segments) {
        return Err(value_err(
            src,
            &p("segments"),
            format!("`segments` must be from 3 to 8192, not {segments}"),
            "use e.g. 64 or 128",
        ));
    }
    let size = |n: usize| -> Result<Vec<f32>, SceneError> {
        let s = o.size.clone().unwrap_or_default();
        if s.len() != n {
            return Err(src.error(
                ErrorKind::Schema,
                &p("size"),
                format!("shape `{shape}` needs `size` with {n} numbers, not {}", s.len()),
                format!("write `size = [{}]`", vec!["1.0"; n].join(", ")),
            ));
        }
        for (k, v) in s.iter().enumerate() {
            positive(src, &format!("{}.{k}", p("size")), *v)?;
        }
        Ok(s)
    };
    let radius = |key: &str, v: Option<f32>| positive(src, &p(key), v.unwrap_or(0.0));

    let (mut analytic, mut heightfield) = (None, None);
    let mut mesh = match shape {
        "sphere" => {
            let r = radius("radius", o.radius)?;
            analytic = Some(Analytic::Sphere { center: matrix.transform_point3(center), radius: r * scale });
            shapes::sphere(center, r, segments)
        }
        "quad" => {
            let s = size(2)?;
            let n = unit(src, &p("normal"), o.normal.unwrap_or_default())?;
            shapes::quad(center, Vec2::new(s[0], s[1]), n)
        }
        "box" => {
            let s = size(3)?;
            shapes::cuboid(center, Vec3::new(s[0], s[1], s[2]))
        }
        "torus" => {
            let major = radius("major_radius", o.major_radius)?;
            let minor = radius("minor_radius", o.minor_radius)?;
            shapes::torus(center, major, minor, segments)
        }
        "open_cylinder" => {
            let r = radius("radius", o.radius)?;
            let h = radius("height", o.height)?;
            shapes::open_cylinder(center, r, h, segments)
        }
        "lathe" => shapes::lathe(center, &profile(o, &p("profile"), src)?, segments),
        "heightfield" => {
            let s = size(2)?;
            let res = o.resolution.unwrap_or(DEFAULT_HEIGHTFIELD_RESOLUTION);
            for (k, n) in res.iter().enumerate() {
                if !(1..=8192).contains(n) {
                    return Err(value_err(
                        src,
                        &format!("{}.{k}", p("resolution")),
                        format!("`resolution` must be from 1 to 8192 cells, not {n}"),
                        "use e.g. [128, 128]",
                    ));
                }
            }
            check_count(src, &p("waves"), o.waves.as_ref().map_or(0, Vec::len), MAX_WAVES)?;
            let mut waves = Vec::new();
            for (k, w) in o.waves.iter().flatten().enumerate() {
                let wp = format!("{}.{k}", p("waves"));
                waves.push(Wave {
                    amplitude: finite(src, &format!("{wp}.amplitude"), w.amplitude)?,
                    kx: finite(src, &format!("{wp}.kx"), w.kx)?,
                    kz: finite(src, &format!("{wp}.kz"), w.kz)?,
                    omega: finite(src, &format!("{wp}.omega"), w.omega)?,
                    phase: finite(src, &format!("{wp}.phase"), w.phase)?,
                });
            }
            let time = finite(src, &p("time"), o.time.unwrap_or(0.0))?;
            let h =
                shapes::Heightfield { center, size: Vec2::new(s[0], s[1]), resolution: res, waves, transform: matrix };
            let mesh = h.mesh(time);
            heightfield = Some(h);
            mesh
        }
        _ => mesh_object(o, &path, rotation, src)?,
    };

    if shape == "mesh" {
        // mesh_object placed it already (rotation and fit, or the full transform).
        if o.fit.is_none() {
            mesh.transform(matrix);
        }
    } else {
        mesh.transform(matrix);
    }
    let horizontal_quad = shape == "quad" && mesh.normals.first().is_some_and(|n| n.y.abs() > 1.0 - 1e-6);
    if shape == "quad" && !horizontal_quad {
        // Edge distances scale with the object; rotation and translation keep them.
        for st in &mut mesh.checker_uv {
            *st *= scale;
        }
    } else {
        mesh.set_checker_uv_xz();
    }
    Ok(Object {
        name: o.name.clone().unwrap_or_else(|| format!("{shape}{i}")),
        material,
        shape,
        mesh,
        analytic,
        heightfield,
    })
}

fn profile(o: &FileObject, path: &str, src: &Source) -> Result<Vec<Vec2>, SceneError> {
    let pts = o.profile.clone().unwrap_or_default();
    check_count(src, path, pts.len(), MAX_PROFILE_POINTS)?;
    if pts.len() < 2 {
        return Err(value_err(
            src,
            path,
            format!("`profile` needs at least 2 points, not {}", pts.len()),
            "give [[r, y], [r, y], ...] in metres",
        ));
    }
    let mut out: Vec<Vec2> = Vec::with_capacity(pts.len());
    for (k, [r, y]) in pts.iter().copied().enumerate() {
        let pp = format!("{path}.{k}");
        let r = finite(src, &pp, r)?;
        let y = finite(src, &pp, y)?;
        if r < 0.0 {
            return Err(value_err(
                src,
                &pp,
                format!("profile point {k} has negative radius {r}"),
                "r is the distance from the +Y axis, at least 0",
            ));
        }
        let q = Vec2::new(r, y);
        if out.last().is_some_and(|prev| (*prev - q).length() < 1e-9) {
            return Err(value_err(
                src,
                &pp,
                format!("profile point {k} repeats the previous point"),
                "remove the duplicate point",
            ));
        }
        out.push(q);
    }
    Ok(out)
}

/// Loads an OBJ object and places it: with `fit`, the transform's rotation, then a
/// uniform scale to the fit's extent and a move to its centre (and floor); without,
/// the caller applies the full transform.
// `!(x > 0.0)` rather than `x <= 0.0`: it also rejects NaN.
#[allow(clippy::neg_cmp_op_on_partial_ord)]
fn mesh_object(o: &FileObject, path: &str, rotation: Quat, src: &Source) -> Result<Mesh, SceneError> {
    let rel = o.file.as_deref().unwrap_or_default();
    let file = relative_to(&src.file, rel);
    let fpath = format!("{path}.file");
    let mut mesh = mesh::load_obj(&file).map_err(|e| {
        if e.kind == ErrorKind::MissingFile || e.line.is_none() {
            src.error(e.kind, &fpath, format!("{}: {}", file.display(), e.message), e.hint.clone())
        } else {
            SceneError::Invalid {
                kind: e.kind,
                at: Location { file: file.clone(), line: e.line, column: None },
                set: None,
                message: format!("{} (mesh of {path}, {})", e.message, src.location(&fpath)),
                hint: e.hint.clone(),
            }
        }
    })?;
    let Some(fit) = &o.fit else {
        return Ok(mesh);
    };
    if let Some(t) = &o.transform {
        if t.translation.is_some() || t.scale.is_some() {
            return Err(src.error(
                ErrorKind::Schema,
                &format!("{path}.transform"),
                "`fit` places the mesh, so `transform` may only rotate it".to_string(),
                "move `translation`/`scale` into `fit.center`/`fit.extent`".to_string(),
            ));
        }
    }
    let extent = positive(src, &format!("{path}.fit.extent"), fit.extent)?;
    let center = point(src, &format!("{path}.fit.center"), fit.center.unwrap_or_default())?;
    mesh.transform(Mat4::from_quat(rotation));
    let (lo, hi) = mesh.bounds();
    let largest = (hi - lo).max_element();
    if !(largest > 0.0) {
        return Err(src.error(
            ErrorKind::Mesh,
            &fpath,
            format!("{}: the mesh has zero size and cannot be fitted", file.display()),
            "remove `fit` or use a mesh with extent".to_string(),
        ));
    }
    let s = extent / largest;
    mesh.transform(
        Mat4::from_translation(center) * Mat4::from_scale(Vec3::splat(s)) * Mat4::from_translation(-(lo + hi) * 0.5),
    );
    if let Some(floor) = fit.floor {
        let floor = finite(src, &format!("{path}.fit.floor"), floor)?;
        let lowest = mesh.bounds().0.y;
        mesh.transform(Mat4::from_translation(Vec3::Y * (floor - lowest)));
    }
    Ok(mesh)
}

#[cfg(test)]
mod tests;
