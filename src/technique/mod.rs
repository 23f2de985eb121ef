//! The technique contract and the frame recipe (../shared/DESIGN.md, "The technique
//! contract"; kajiya's `renderers/*.rs` called from one `world_render_passes.rs`, Falcor's
//! render passes that declare what they need).
//!
//! Every technique, the baseline passes included, is one [`Registration`] in [`TECHNIQUES`]:
//!
//! - **plan**: given the scene, the passes it needs, each tagged with the [`Stage`] of the
//!   frame it runs in and the reason the scene requires it (`prism passes` prints these);
//!   no pass, no technique: it is never created;
//! - **create**: its resources, from the frame's shared resources in [`Setup`];
//! - **record** ([`Technique::record`]): its passes of one stage into the frame graph,
//!   reading the frame's shared inputs ([`FrameInputs`]);
//! - **react** ([`Technique::begin_frame`], [`Technique::objects_moved`]): what it rebuilds
//!   when something changes.
//!
//! The frame recipe ([`recipe`]) is the one place the order lives: the stages in [`RECIPE`]
//! order, and within a stage the techniques in registration order. The renderer records
//! the same steps it planned, and checks after every step, in every build, that the
//! technique recorded exactly the passes it planned; so `prism passes`, the timings and the
//! recorded frame cannot disagree.
//!
//! Adding a technique: one file with its plan, its creation and its `impl Technique`, and
//! one line in [`TECHNIQUES`] (docs/architecture.md walks through it).
use std::any::Any;
use std::ops::Range;
use std::sync::Arc;

use glam::Vec3;

use crate::frame::gpu_scene::GpuScene;
use crate::frame::targets::Targets;
use crate::gpu::{DescriptorSet, DescriptorSetLayout, GpuContext, Sampler, Spec};
use crate::graph::{Frame, FrameGraph, ImageId};
use crate::scene::{Environment, Light, Material, Scene};

pub mod baseline;
pub mod caustics;
pub mod eikonal;
pub mod impostor;
pub mod raytrace;
pub mod refraction;

use caustics::photon_buffer::PhotonCaustics;
use refraction::refractor_layers::DebugTarget;

/// Where in the frame a pass runs. A stage's passes may read what every earlier stage
/// wrote: shadows and caustics before the surfaces are shaded, the opaque image before the
/// specular objects are composited into it, everything before the tone map.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash, serde::Serialize)]
pub enum Stage {
    /// Distance-to-light maps of every light.
    Shadows,
    /// Caustic light on the diffuse receivers (caustic maps, photon buffers, light maps).
    Caustics,
    /// The first visible surface of every object (G-buffer).
    Surfaces,
    /// Diffuse shading and the environment behind everything.
    Shading,
    /// Light added to the shaded surfaces after shading (light maps, volume irradiance).
    Lighting,
    /// The dielectrics composited into the image.
    Refraction,
    /// The mirrors and conductors composited into the image.
    Reflection,
    /// Inhomogeneous media (eikonal view rays).
    Volume,
    /// Linear radiance to the displayed image.
    Tonemap,
}

impl Stage {
    /// Whether the stage's passes work at the image's size. The light-space stages (shadows,
    /// caustics) render from the lights into the atlases and never touch an image-sized
    /// target (the renderer checks this for every step it records), so a resize keeps their
    /// techniques.
    pub fn is_image_space(self) -> bool {
        !matches!(self, Stage::Shadows | Stage::Caustics)
    }
}

/// The frame recipe's order of stages.
pub const RECIPE: [Stage; 9] = [
    Stage::Shadows,
    Stage::Caustics,
    Stage::Surfaces,
    Stage::Shading,
    Stage::Lighting,
    Stage::Refraction,
    Stage::Reflection,
    Stage::Volume,
    Stage::Tonemap,
];

/// Every technique prism knows, in the order they are created and, within a stage,
/// recorded. A technique's creation may read what the ones before it planned.
pub const TECHNIQUES: &[Registration] = &[
    baseline::shadow_map::TECHNIQUE,
    caustics::caustics_map::TECHNIQUE,
    caustics::photon_buffer::TECHNIQUE,
    impostor::impostor_lightmap::TECHNIQUE,
    baseline::gbuffer::TECHNIQUE,
    baseline::deferred_shading::TECHNIQUE,
    raytrace::CAUSTICS,
    baseline::specular_single::REFRACTION,
    refraction::refraction_wyman::TECHNIQUE,
    refraction::refraction_hu_qin::TECHNIQUE,
    refraction::refraction_water::TECHNIQUE,
    impostor::distance_impostor::REFRACTION,
    raytrace::REFRACTION,
    baseline::specular_single::REFLECTION,
    impostor::distance_impostor::REFLECTION,
    raytrace::REFLECTION,
    eikonal::eikonal_view::TECHNIQUE,
    raytrace::VOLUME,
    baseline::tonemap::TECHNIQUE,
];

/// One pass a technique needs for a scene, and why.
#[derive(Clone, Debug, PartialEq, Eq, serde::Serialize)]
pub struct PlannedPass {
    /// Snake_case: also the pass's timing name and its golden image's name.
    pub name: &'static str,
    /// Which objects, lights or settings require the pass.
    pub reason: String,
}

impl PlannedPass {
    pub fn new(name: &'static str, reason: impl Into<String>) -> Self {
        PlannedPass { name, reason: reason.into() }
    }
}

/// The [`Registration`] of a technique selected by `key`, created by `T::new(&mut Setup)`,
/// whose resources depend on its `[render.<table>]`s and the placement
/// ([`tables_and_placement`]).
macro_rules! registration {
    ($key:expr, $plan:expr, $technique:ty, [$($table:literal),+]) => {
        $crate::technique::Registration {
            key: $key,
            plan: $plan,
            create: |s| Ok(Box::new(<$technique>::new(s)?)),
            inputs: |scene| $crate::technique::tables_and_placement(scene, &[$($table),+]),
        }
    };
}
pub(crate) use registration;

/// A technique's entry in [`TECHNIQUES`].
pub struct Registration {
    /// What selects it: `refraction = "wyman"`, or the baseline pass's name.
    pub key: &'static str,
    /// The passes it needs for a scene, each with its stage; empty: the technique is not
    /// created. Pure CPU (`prism passes` calls it without a device).
    pub plan: fn(&Scene) -> Vec<(Stage, PlannedPass)>,
    /// Its resources. Called only when `plan` returned passes.
    pub create: fn(&mut Setup<'_>) -> Result<Box<dyn Technique>, RenderError>,
    /// What its resources depend on besides its own plan and the frame's shared resources
    /// (the GPU scene, the targets): usually its `[render.<table>]`s ([`tables`]), and
    /// whether it is built from positions. When a scene changes and neither this nor its
    /// plan did, the running technique is kept.
    pub inputs: fn(&Scene) -> Inputs,
}

/// What a technique's creation can use: the device, the scene, the frame's shared resources
/// and the whole plan (a technique that adapts to another's presence reads it here).
pub struct Setup<'a> {
    pub ctx: &'a Arc<GpuContext>,
    pub scene: &'a Scene,
    pub gpu: &'a GpuScene,
    pub graph: &'a mut FrameGraph,
    /// The frame descriptor set's layout (set 0 of every pipeline that reads the frame).
    pub frame_layout: &'a DescriptorSetLayout,
    pub targets: &'a Targets,
    /// Nearest-neighbour, clamp-to-edge: how techniques read each other's targets.
    pub nearest: &'a Sampler,
    /// Hu & Qin 2007 §3's caustic textures and rectangles, bound in the frame set.
    pub photon_caustics: &'a PhotonCaustics,
    pub plan: &'a [PlannedPass],
    /// Frames in flight: techniques with per-frame state keep one copy per slot.
    pub slots: usize,
    /// What a technique keeps across its own re-creation.
    pub cache: &'a mut Cache,
}

/// When a technique renders what it keeps from frame to frame (shadow maps, impostor
/// textures, caustic maps, light maps): in its first frame and in the frame after anything they show
/// changed, and in no other. Hu & Qin 2007 §4: "For a static scene, it is unnecessary to
/// compute caustics, shadow, RECT_i, and TEX_i during rendering"; `render.update =
/// "every_frame"` makes every frame a change (the papers' timings, which assume fully dynamic
/// scenes). What depends on where things are is rebuilt with the technique (its
/// [`Inputs::placement`]); what changes in place reaches it through
/// [`Technique::objects_moved`] and [`Technique::contents_changed`].
#[derive(Debug)]
pub struct Regeneration {
    pending: bool,
    rendering: bool,
    generations: u32,
}

impl Default for Regeneration {
    fn default() -> Self {
        Regeneration { pending: true, rendering: false, generations: 0 }
    }
}

impl Regeneration {
    /// What the kept results show changed: render them with the next frame.
    pub fn changed(&mut self) {
        self.pending = true;
    }

    /// Decide whether the frame about to be recorded renders them.
    pub fn begin_frame(&mut self) {
        self.rendering = std::mem::take(&mut self.pending);
        self.generations += u32::from(self.rendering);
    }

    /// Whether the frame being recorded renders them.
    pub fn rendering(&self) -> bool {
        self.rendering
    }

    /// How many frames rendered them.
    pub fn generations(&self) -> u32 {
        self.generations
    }
}

/// The planned passes `names` of a frame that renders nothing new: recorded empty, so that the
/// frame still has every pass of the recipe (and its timings a zero for each).
pub fn record_kept(frame: &mut Frame<'_, '_>, names: &[&str]) {
    for name in names {
        frame.pass(name).record(|_| {});
    }
}

/// Results a technique keeps across its own re-creation, by type and key: what is expensive
/// and depends on less than the technique does. The eikonal light simulation depends on the
/// volume, the lights and its settings; the technique around it also depends on the image
/// size and on the objects near the volume, and is re-created when they change, without
/// simulating again.
#[derive(Default)]
pub struct Cache {
    entries: std::collections::HashMap<(std::any::TypeId, u64), (std::rc::Rc<dyn Any>, u64)>,
    generation: u64,
}

impl Cache {
    /// The entry of type `T` under `key`, made by `make` when there is none.
    pub fn get_or_try_insert<T: 'static, E>(
        &mut self,
        key: u64,
        make: impl FnOnce() -> Result<T, E>,
    ) -> Result<std::rc::Rc<T>, E> {
        let id = (std::any::TypeId::of::<T>(), key);
        if let Some((entry, used)) = self.entries.get_mut(&id) {
            *used = self.generation;
            if let Ok(t) = entry.clone().downcast::<T>() {
                return Ok(t);
            }
        }
        let t = std::rc::Rc::new(make()?);
        self.entries.insert(id, (t.clone(), self.generation));
        Ok(t)
    }

    /// [`Cache::get_or_try_insert`], with the host milliseconds `make` took when it ran: what
    /// the entry cost once, reported by the techniques that hold it
    /// ([`Technique::once_costs`]).
    pub fn get_or_try_insert_timed<T: 'static, E>(
        &mut self,
        key: u64,
        make: impl FnOnce() -> Result<T, E>,
    ) -> Result<std::rc::Rc<Timed<T>>, E> {
        self.get_or_try_insert(key, || {
            let start = std::time::Instant::now();
            let value = make()?;
            Ok(Timed { value, ms: start.elapsed().as_secs_f64() * 1e3 })
        })
    }

    /// Start a round of creations (a renderer's, or an update's).
    pub(crate) fn begin(&mut self) {
        self.generation += 1;
    }

    /// End the round: keep what this round asked for and what a running technique still
    /// holds; drop the rest.
    pub(crate) fn end(&mut self) {
        let generation = self.generation;
        self.entries.retain(|_, (entry, used)| *used == generation || std::rc::Rc::strong_count(entry) > 1);
    }
}

/// A key for [`Cache`]: the hash of what the cached result depends on, from its `Debug` form.
pub fn cache_key(inputs: &impl std::fmt::Debug) -> u64 {
    use std::hash::{Hash, Hasher};
    let mut h = std::collections::hash_map::DefaultHasher::new();
    format!("{inputs:?}").hash(&mut h);
    h.finish()
}

impl Setup<'_> {
    /// Whether any technique planned the pass `name`.
    pub fn planned(&self, name: &str) -> bool {
        has(self.plan, name)
    }
}

/// What every recording reads: the scene's GPU data, the frame's targets and descriptor
/// set, and what earlier stages produced.
pub struct FrameInputs<'a> {
    pub scene: &'a GpuScene,
    pub targets: &'a Targets,
    pub photon_caustics: &'a PhotonCaustics,
    pub frame_set: DescriptorSet,
    /// The frame-in-flight slot being recorded.
    pub slot: usize,
    /// The shadow atlas, when a shadow pass wrote it this frame.
    pub shadow_atlas: Option<ImageId>,
    /// Seconds since the last frame (the window's temporal adaptation); `None`: converged.
    pub dt: Option<f32>,
    /// Every object's current bounding sphere (centre, radius), in scene order: the tightest
    /// about its box's centre ([`impostor::distance_impostor::tight_object_bounds`]).
    pub object_bounds: &'a [(Vec3, f32)],
    /// Every object's current bounding box (centre, half extents), in scene order
    /// ([`impostor::distance_impostor::object_box`]).
    pub object_boxes: &'a [(Vec3, Vec3)],
    /// The camera's view-projection this frame (the frame uniforms').
    pub view_proj: glam::Mat4,
    /// The camera's position and unit viewing direction this frame.
    pub eye: Vec3,
    pub forward: Vec3,
}

/// A created technique: what the frame recipe calls.
pub trait Technique: Any {
    /// Record this technique's passes of `stage` (exactly those its plan gave that stage).
    fn record<'a>(&'a self, stage: Stage, frame: &mut Frame<'_, 'a>, inputs: &FrameInputs<'a>);

    /// What the technique keeps from frame to frame and renders again after any change (the
    /// three hooks below drive it unless the technique overrides them).
    fn kept(&mut self) -> Option<&mut Regeneration> {
        None
    }

    /// Called before every frame is recorded (a cache decides here whether to render again).
    fn begin_frame(&mut self) {
        if let Some(k) = self.kept() {
            k.begin_frame();
        }
    }

    /// Objects moved: every object's (centre, bounding radius), in scene order.
    fn objects_moved(&mut self, _bounds: &[(Vec3, f32)]) {
        if let Some(k) = self.kept() {
            k.changed();
        }
    }

    /// Something a kept result may show changed in place, with no object moved by
    /// [`Self::objects_moved`]: the material values were rewritten, the water's vertices
    /// animated, or (`render.update = "every_frame"`) a new frame began.
    fn contents_changed(&mut self) {
        if let Some(k) = self.kept() {
            k.changed();
        }
    }

    /// The scene was updated and the technique kept: what it varies from frame to frame (the
    /// raytrace technique's photons) starts again, as in a technique created for the new
    /// scene.
    fn restart(&mut self) {}

    /// The camera moved (its position, direction or field of view): what the technique
    /// averages over the frames of one view starts again.
    fn camera_moved(&mut self) {}

    /// The frames averaged into the image the technique shows (the raytrace technique's
    /// running mean, `render.raytrace.accumulate`), as of the last frame begun; `None`: it
    /// shows every frame as rendered.
    fn accumulated(&self) -> Option<u32> {
        None
    }

    /// Whether work that spans frames is left ([`Self::prepare`]).
    fn preparing(&self) -> bool {
        false
    }

    /// Work that spans frames (the eikonal light simulation), done before a frame is recorded
    /// with no frame in flight: continue it until `deadline`, or to its end without one
    /// (headless rendering), so that the frame shows what it has computed so far.
    fn prepare(
        &mut self,
        _ctx: &Arc<GpuContext>,
        _graph: &mut FrameGraph,
        _deadline: Option<std::time::Instant>,
    ) -> Result<(), RenderError> {
        Ok(())
    }

    /// Intermediate images a test or a debug view can read back.
    fn debug_targets(&self) -> &[DebugTarget] {
        &[]
    }

    /// What its creation computed outside the frame's passes and keeps until a change (the
    /// eikonal light simulation, Wyman's d_N), as measured when it was computed. A cached
    /// pass inside the frame (a distance impostor's map) is timed by the frame's timestamps
    /// instead: it does work in the first frame and none after. A result shared through the
    /// cache is named alike by every technique holding it, and counted once.
    fn once_costs(&self) -> Vec<OnceCost> {
        Vec::new()
    }
}

/// A cached result and the host milliseconds it took to make, uploads and waits included.
pub struct Timed<T> {
    pub value: T,
    pub ms: f64,
}

/// A cost paid once per change of what a result depends on, not every frame.
#[derive(Clone, Debug, serde::Serialize)]
pub struct OnceCost {
    /// The pass, or the computation outside the frame graph.
    pub name: String,
    pub ms: f64,
    /// `gpu`: device timestamps (on lavapipe, CPU time like every pass); `cpu`: wall-clock
    /// time on the host.
    pub clock: &'static str,
    /// Which change runs it again, from what its cache is keyed by.
    pub rerun_on: &'static str,
}

/// What the tracers' geometry (the reference's BVH and buffers, shared by `raytrace` and
/// `water` through the cache) cost to build: keyed by the objects' triangles, spheres and
/// materials and the volume, so it is built again when an object moves or changes, never
/// for a light or the camera.
pub fn trace_geometry_cost(geometry: &Timed<crate::reference::TraceGeometry>) -> OnceCost {
    OnceCost { name: "trace_geometry".into(), ms: geometry.ms, clock: "cpu", rerun_on: "object change" }
}

/// One step of the recipe: one technique's passes of one stage.
#[derive(Clone, Debug)]
pub struct Step {
    /// Index into [`TECHNIQUES`].
    pub technique: usize,
    pub stage: Stage,
    /// This step's passes in [`Recipe::passes`].
    pub passes: Range<usize>,
}

/// The frame of a scene: every pass in order, and the steps that record them.
#[derive(Clone, Debug)]
pub struct Recipe {
    pub passes: Vec<PlannedPass>,
    pub steps: Vec<Step>,
}

impl Recipe {
    /// Whether technique `index` of [`TECHNIQUES`] has any pass in this frame.
    pub fn uses(&self, index: usize) -> bool {
        self.steps.iter().any(|s| s.technique == index)
    }

    /// Whether technique `index` has a pass at the image's size ([`Stage::is_image_space`]):
    /// a resize re-creates it.
    pub fn is_image_space(&self, index: usize) -> bool {
        self.steps.iter().any(|s| s.technique == index && s.stage.is_image_space())
    }
}

/// The frame recipe for `scene`: each technique's plan, ordered by [`RECIPE`] stage, then
/// by registration.
pub fn recipe(scene: &Scene) -> Recipe {
    let planned: Vec<Vec<(Stage, PlannedPass)>> = TECHNIQUES.iter().map(|t| (t.plan)(scene)).collect();
    let mut recipe = Recipe { passes: Vec::new(), steps: Vec::new() };
    for stage in RECIPE {
        for (technique, passes) in planned.iter().enumerate() {
            let start = recipe.passes.len();
            recipe.passes.extend(passes.iter().filter(|(s, _)| *s == stage).map(|(_, p)| p.clone()));
            if recipe.passes.len() > start {
                recipe.steps.push(Step { technique, stage, passes: start..recipe.passes.len() });
            }
        }
    }
    recipe
}

/// Whether the pass list contains `name`.
pub fn has(plan: &[PlannedPass], name: &str) -> bool {
    plan.iter().any(|p| p.name == name)
}

pub use crate::frame::RenderError;

/// The specialisation constants that describe the scene's environment and lights
/// (glsl/include/common.glsl: ENVIRONMENT, LIGHT_COUNT, LIGHT_KINDS), for every pass that looks
/// up the environment or lights diffuse surfaces. Compiled in, the lookups keep only the
/// environment kind and the light kinds the scene has, and the light loop its exact count: a
/// CPU device runs every side of a branch, and on sphere_nearby deferred shading took 2.5x its
/// specialised time choosing among them per pixel (docs/BENCHMARKS.md). The environment, the
/// number of lights and their kinds are all in the renderer's shared fingerprint
/// (src/renderer/update.rs), so a change to any of them re-creates every pass with new values.
pub fn scene_specialization(scene: &Scene) -> [(&'static str, Spec); 3] {
    use crate::{
        ENVIRONMENT_CONSTANT, ENVIRONMENT_GRID, ENVIRONMENT_MAP, LIGHT_KINDS_ANY, LIGHT_KINDS_DIRECTIONAL,
        LIGHT_KINDS_POINT,
    };
    let environment = match &scene.environment {
        Environment::Constant(_) => ENVIRONMENT_CONSTANT,
        Environment::Grid => ENVIRONMENT_GRID,
        // A 1x1 image is the constant its one texel holds (the lookup's texel fetch).
        Environment::Image { width: 1, height: 1, .. } => ENVIRONMENT_CONSTANT,
        Environment::Image { .. } => ENVIRONMENT_MAP,
    };
    let kinds = scene.lights.iter().fold(0, |k, l| {
        k | match l {
            Light::Point { .. } => LIGHT_KINDS_POINT,
            Light::Directional { .. } => LIGHT_KINDS_DIRECTIONAL,
        }
    });
    [
        ("ENVIRONMENT", Spec::U32(environment)),
        ("LIGHT_COUNT", Spec::U32(scene.lights.len() as u32)),
        // Without lights the loop never runs; either kind compiles.
        ("LIGHT_KINDS", Spec::U32(if kinds == 0 { LIGHT_KINDS_ANY } else { kinds })),
    ]
}

/// `[render.<technique>]` parsed into its typed parameters, as a [`RenderError`].
pub fn params<T>(
    technique: &'static str,
    parsed: Result<T, crate::scene::techniques::ParamError>,
) -> Result<T, RenderError> {
    parsed.map_err(|error| RenderError::Param { technique, error })
}

/// The parameter tables `[render.<name>]` of `names` as they are in `scene` (absent: empty),
/// for [`Registration::inputs`].
pub fn tables(scene: &Scene, names: &[&str]) -> String {
    names.iter().map(|n| format!("[{n}] {:?}\n", scene.render.params.get(*n))).collect()
}

/// What a technique's resources depend on besides its plan and the frame's shared
/// resources ([`Registration::inputs`]).
#[derive(Clone, Debug, Default, PartialEq, Eq, Hash)]
pub struct Inputs {
    /// Its settings, usually its `[render.<table>]`s as they are in the scene ([`tables`]).
    pub settings: String,
    /// Whether it is built from where things are ([`placement_hash`]): impostor rectangles,
    /// light frusta, shadow faces. It is re-created when something moves.
    pub placement: bool,
}

impl Inputs {
    pub fn settings(settings: impl Into<String>) -> Self {
        Inputs { settings: settings.into(), placement: false }
    }
}

/// Where everything is: every vertex of every object, the analytic shapes, the lights and the
/// camera position (the GPU scene's bounds include it), as one hash. Computed once per
/// update, for every technique whose [`Inputs::placement`] is set.
pub fn placement_hash(scene: &Scene) -> u64 {
    use std::hash::{Hash, Hasher};
    let mut h = std::collections::hash_map::DefaultHasher::new();
    for o in &scene.objects {
        for (p, n) in o.mesh.positions.iter().zip(&o.mesh.normals) {
            (p.to_array().map(f32::to_bits), n.to_array().map(f32::to_bits)).hash(&mut h);
        }
        for uv in &o.mesh.checker_uv {
            uv.to_array().map(f32::to_bits).hash(&mut h);
        }
        format!("{:?}", o.analytic).hash(&mut h);
    }
    format!("{:?} {:?}", scene.lights, scene.camera.position).hash(&mut h);
    h.finish()
}

/// [`Registration::inputs`] of a technique built from where things are and nothing else.
pub fn placement(_: &Scene) -> Inputs {
    Inputs { settings: String::new(), placement: true }
}

/// [`tables`] and placement: the inputs of a technique built from its settings and from
/// where things are.
pub fn tables_and_placement(scene: &Scene, names: &[&str]) -> Inputs {
    Inputs { settings: tables(scene, names), placement: true }
}

/// [`Registration::inputs`] of a technique that depends on nothing but its plan.
pub fn no_inputs(_: &Scene) -> Inputs {
    Inputs::default()
}

/// Names of the objects whose material satisfies `pred`, for the plans' reasons.
pub fn object_names(scene: &Scene, pred: impl Fn(&Material) -> bool) -> Vec<String> {
    scene.objects.iter().filter(|o| pred(&scene.materials[o.material])).map(|o| o.name.clone()).collect()
}

pub fn diffuse_names(scene: &Scene) -> Vec<String> {
    object_names(scene, Material::is_diffuse)
}

pub fn dielectric_names(scene: &Scene) -> Vec<String> {
    object_names(scene, |m| matches!(m, Material::Dielectric { .. }))
}

pub fn metal_names(scene: &Scene) -> Vec<String> {
    object_names(scene, |m| matches!(m, Material::Mirror { .. } | Material::Conductor { .. }))
}

/// The specular objects (dielectrics, then mirrors and conductors) that cast caustics.
pub fn specular_names(scene: &Scene) -> Vec<String> {
    let mut v = dielectric_names(scene);
    v.extend(metal_names(scene));
    v
}

/// The diffuse receivers and the specular casters, when the scene can show a caustic with
/// the caustics technique `key` selected: a light, a receiver and a caster.
pub fn caustic_objects(scene: &Scene, key: &str) -> Option<(Vec<String>, Vec<String>)> {
    if scene.render.caustics != key || scene.lights.is_empty() {
        return None;
    }
    let (diffuse, specular) = (diffuse_names(scene), specular_names(scene));
    (!diffuse.is_empty() && !specular.is_empty()).then_some((diffuse, specular))
}

/// The dielectrics' names, when the scene has one and the refraction technique `key` is
/// selected.
pub fn refracting_objects(scene: &Scene, key: &str) -> Option<Vec<String>> {
    let names = dielectric_names(scene);
    (scene.render.refraction == key && !names.is_empty()).then_some(names)
}

/// The mirrors' and conductors' names, when the scene has one and the reflection technique
/// `key` is selected.
pub fn reflecting_objects(scene: &Scene, key: &str) -> Option<Vec<String>> {
    let names = metal_names(scene);
    (scene.render.reflection == key && !names.is_empty()).then_some(names)
}

/// `passes`, all of one stage: a plan.
pub fn in_stage(stage: Stage, passes: impl IntoIterator<Item = PlannedPass>) -> Vec<(Stage, PlannedPass)> {
    passes.into_iter().map(|p| (stage, p)).collect()
}

pub fn list(v: &[String]) -> String {
    v.join(", ")
}

pub fn describe_light(i: usize, l: &Light) -> String {
    match l {
        Light::Point { position: p, .. } => {
            format!("light {i} (point at ({}, {}, {}))", p.x, p.y, p.z)
        }
        Light::Directional { direction: d, .. } => {
            format!("light {i} (directional ({:.3}, {:.3}, {:.3}))", d.x, d.y, d.z)
        }
    }
}

/// Every light described, joined by `sep`.
pub fn describe_lights(scene: &Scene, sep: &str) -> String {
    scene.lights.iter().enumerate().map(|(i, l)| describe_light(i, l)).collect::<Vec<_>>().join(sep)
}
