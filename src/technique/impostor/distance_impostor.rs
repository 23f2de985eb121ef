//! Szirmay-Kalos, Aszódi, Lazányi, Premecz 2005, "Approximate Ray-Tracing on the GPU with
//! Distance Impostors" (Eurographics 2005), §2-4 and §6: localized environment mapping.
//! `render.reflection = "impostor"` and `render.refraction = "impostor"`, parameters
//! `[render.impostor]` ([`ImpostorParams`]).
//!
//! - [`ImpostorMap`] with [`MapContent::Environment`] (`*_impostor_map`): the *distance
//!   impostor* (§2, §3), a cube map around a reference point (the specular objects' centre)
//!   holding the radiance of the visible diffuse surface, exactly as deferred shading computes
//!   it (glsl/include/lighting.glsl), and the distance of that surface from the reference
//!   point, computed per pixel (§3), in the alpha channel or in a separate R32F cube (§6). The
//!   specular objects themselves are left out of their own map.
//! - [`ImpostorMap`] with [`MapContent::Refractor`] (`refraction_impostor_refractor_map`): the
//!   *refractor map* (§4), the refractor's own surface seen from its centre: outward normal
//!   and distance. It moves with the object, so it is rendered once.
//! - `reflection_impostor` (glsl/impostor/reflect.frag): R = reflect(V, N), Hit() (§3,
//!   glsl/include/impostor.glsl: d_p, d_l of Eq. 4, Eq. 6 by false position), the radiance
//!   towards the hit, times the conductor Fresnel term (§3's approximation or exact).
//! - `refraction_impostor` (glsl/impostor/refract.frag): the double refraction of §4 (Fig. 8).
//! - `oracle` (an analysis tool, [`ImpostorOracle`]): `"hit"` replaces `Hit()` in the
//!   environment impostor by the exact tracer's closest hit (the shading passes then run
//!   glsl/impostor/*_oracle.frag with the tracer's buffers in a set 2 of their own,
//!   src/technique/refraction/oracle.rs), so that `prism ablation --technique impostor` measures
//!   `Hit()`'s share of the error.
//!
//! Regeneration (§6: "this preparation phase is usually not executed in each frame, only if
//! the object movements are large enough"): [`ImpostorMap::objects_moved`] re-centres a map and
//! marks it for rendering when its objects' centre left the reference point by more than
//! `regenerate_distance` bounding radii; otherwise the map pass records nothing that frame.
//! `render.impostor.maps` (§6: "a single environment map for all of them, or ... a separate
//! map for each of them"): `"shared"` gives an effect one map for all its specular objects,
//! with its reference point at their mean centre and all of them left out; `"per_object"`
//! gives each specular object its own map (and refractor map) centred on it, holding
//! everything but that object, each regenerated only when its own object moves. The map and
//! shading passes stay one pass each: the map pass renders every map due this frame, the
//! shading pass draws once per object, picking the object's pixels by the G-buffer's object
//! index (glsl/gbuffer/gbuffer.frag).
use std::sync::Arc;

use glam::{Mat4, Vec3};

use crate::frame::gpu_scene::{cube_face_views, GpuScene};
use crate::frame::targets::{Targets, DEPTH_FORMAT};
use crate::gpu::{
    vk, Access, Blend, Buffer, Clear, Cmd, ComputePipeline, DepthState, DescriptorSet, GpuContext, GpuResult,
    GraphicsPipeline, GraphicsPipelineDesc, Image, ImageDesc, ImageViewKind, RenderTarget, Sampler, SamplerDesc, Spec,
};
use crate::graph::{Bindings, BoundSet, Frame, FrameGraph, ImageId, PassBuilder};
use crate::scene::techniques::{ImpostorFresnel, ImpostorMaps, ImpostorOracle, ImpostorParams, ImpostorUpdate};
use crate::scene::{Analytic, Material, Scene};
use crate::shader_structs::{ImpostorProbePush, MapPush, ShadePush};
use crate::technique::refraction::oracle::Oracle;
use crate::technique::scene_specialization;
use crate::technique::{
    in_stage, list, params, reflecting_objects, refracting_objects, registration, FrameInputs, OnceCost, PlannedPass,
    Registration, RenderError, Setup, Stage, Technique,
};
use crate::{
    BINDING_IMPOSTOR_DISTANCE, BINDING_IMPOSTOR_PROBE, BINDING_IMPOSTOR_RADIANCE, BINDING_IMPOSTOR_REFRACTOR,
    IMPOSTOR_PROBE_FRESNEL, IMPOSTOR_PROBE_HIT, WORKGROUP_2D,
};

pub const REFLECTION_IMPOSTOR_MAP: &str = "reflection_impostor_map";
pub const REFLECTION_IMPOSTOR: &str = "reflection_impostor";
pub const REFRACTION_IMPOSTOR_MAP: &str = "refraction_impostor_map";
pub const REFRACTION_IMPOSTOR_REFRACTOR_MAP: &str = "refraction_impostor_refractor_map";
pub const REFRACTION_IMPOSTOR: &str = "refraction_impostor";

/// `render.refraction = "impostor"` (§4), parameters `[render.impostor]`.
pub const REFRACTION: Registration =
    registration!("refraction = \"impostor\"", plan_refraction, ImpostorRefraction, ["impostor"]);

/// `render.reflection = "impostor"` (§3), parameters `[render.impostor]`.
pub const REFLECTION: Registration =
    registration!("reflection = \"impostor\"", plan_reflection, ImpostorReflection, ["impostor"]);

fn impostor_params(s: &Setup<'_>) -> Result<ImpostorParams, RenderError> {
    params("impostor", ImpostorParams::from_settings(&s.scene.render))
}

fn plan_refraction(scene: &Scene) -> Vec<(Stage, PlannedPass)> {
    let Some(dielectric) = refracting_objects(scene, "impostor") else {
        return Vec::new();
    };
    let list = list(&dielectric);
    in_stage(
        Stage::Refraction,
        [
            PlannedPass::new(
                REFRACTION_IMPOSTOR_MAP,
                format!("distance impostor around dielectric {list} (render.refraction = \"impostor\")"),
            ),
            PlannedPass::new(
                REFRACTION_IMPOSTOR_REFRACTOR_MAP,
                format!("refractor map (distance + normal cube) of {list}"),
            ),
            PlannedPass::new(
                REFRACTION_IMPOSTOR,
                format!("double refraction of {list} through the refractor map (Szirmay-Kalos et al. 2005, §4)"),
            ),
        ],
    )
}

fn plan_reflection(scene: &Scene) -> Vec<(Stage, PlannedPass)> {
    let Some(metal) = reflecting_objects(scene, "impostor") else {
        return Vec::new();
    };
    let list = list(&metal);
    in_stage(
        Stage::Reflection,
        [
            PlannedPass::new(
                REFLECTION_IMPOSTOR_MAP,
                format!(
                    "distance impostor (radiance + distance cube) around mirror/conductor {list} \
                         (render.reflection = \"impostor\")"
                ),
            ),
            PlannedPass::new(
                REFLECTION_IMPOSTOR,
                format!("localized reflection of {list} (Hit(), Szirmay-Kalos et al. 2005)"),
            ),
        ],
    )
}

/// The reflection and the refraction technique record and react alike: their maps follow
/// the objects (§6) and are rendered again at the start of a frame when needed.
macro_rules! impostor_technique {
    ($t:ty) => {
        impl Technique for $t {
            fn record<'a>(&'a self, _: Stage, frame: &mut Frame<'_, 'a>, inputs: &FrameInputs<'a>) {
                self.record(frame, inputs.scene, inputs.targets, inputs.frame_set, inputs.shadow_atlas);
            }

            fn begin_frame(&mut self) {
                <$t>::begin_frame(self);
            }

            fn objects_moved(&mut self, bounds: &[(Vec3, f32)]) {
                <$t>::objects_moved(self, bounds);
            }

            fn contents_changed(&mut self) {
                <$t>::contents_changed(self);
            }

            fn once_costs(&self) -> Vec<OnceCost> {
                self.oracle.as_ref().map(|o| o.cost()).into_iter().collect()
            }
        }
    };
}
impostor_technique!(ImpostorRefraction);
impostor_technique!(ImpostorReflection);

/// Cleared distance where no surface is seen (src/shader_shared.rs, shared with the shaders).
pub const NO_SURFACE: f32 = crate::IMPOSTOR_NO_SURFACE;
/// Radiance (rgb) + distance (a), or the refractor map's normal (xyz) + distance (w).
pub const CUBE_FORMAT: vk::Format = vk::Format::R32G32B32A32_SFLOAT;
pub const DISTANCE_FORMAT: vk::Format = vk::Format::R32_SFLOAT;

/// `ShadePush::object` of a shared map: every pixel of the pass's materials.
const ALL_OBJECTS: u32 = u32::MAX;

/// Centre and bounding radius of an object: the exact sphere's, or its mesh's bounding box.
pub fn object_bounds(scene: &Scene, object: usize) -> (Vec3, f32) {
    let o = &scene.objects[object];
    if let Some(Analytic::Sphere { center, radius }) = o.analytic {
        return (center, radius);
    }
    let (mut lo, mut hi) = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
    for &p in &o.mesh.positions {
        lo = lo.min(p);
        hi = hi.max(p);
    }
    if lo.x > hi.x {
        return (Vec3::ZERO, 0.0);
    }
    ((lo + hi) * 0.5, (hi - lo).length() * 0.5)
}

/// The box (centre, half extents) around an object, about [`object_bounds`]' centre: the
/// exact sphere's, or its mesh's. A heightfield's is its bounding sphere's cube: the window
/// displaces its vertices on the GPU, beyond the ones held here.
pub fn object_box(scene: &Scene, object: usize) -> (Vec3, Vec3) {
    let o = &scene.objects[object];
    let (centre, radius) = object_bounds(scene, object);
    if o.heightfield.is_some() || o.mesh.positions.is_empty() {
        return (centre, Vec3::splat(radius));
    }
    if let Some(Analytic::Sphere { radius, .. }) = o.analytic {
        return (centre, Vec3::splat(radius));
    }
    let (lo, hi) = o.mesh.bounds();
    (centre, (hi - lo) * 0.5)
}

/// The same centre as [`object_bounds`] with the smallest radius about it that holds every
/// vertex: the farthest vertex's distance. The passes that skip work outside a sphere (the
/// shading passes' covers, the G-buffer's and the shadow maps' culling) take this one: a
/// box's corner is often empty (for bunny_env's bunny the radius is 1.34 against the box's
/// 1.59). The distance impostors and light maps keep [`object_bounds`], the radius their
/// maps and frusta were measured with. A heightfield keeps the box's radius too: the window
/// displaces its vertices on the GPU, beyond the ones held here.
pub fn tight_object_bounds(scene: &Scene, object: usize) -> (Vec3, f32) {
    let o = &scene.objects[object];
    let (centre, radius) = object_bounds(scene, object);
    if o.analytic.is_some() || o.heightfield.is_some() || o.mesh.positions.is_empty() {
        return (centre, radius);
    }
    let farthest = o.mesh.positions.iter().map(|p| p.distance(centre)).fold(0.0, f32::max);
    // No tighter than the vertices allow, and never looser than the box's.
    (centre, farthest.min(radius))
}

/// One light-mapped part of an object in the uv map: (first index within the object's
/// indices, index count, light-map slot + 1, chart row a, chart row b).
pub type UvChart = (u32, u32, u32, [f32; 4], [f32; 4]);

/// What a map stores.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MapContent {
    /// §3: radiance and distance of everything but the map's own objects.
    Environment,
    /// §4: outward normal and distance of the map's own objects only.
    Refractor,
    /// §5: the uv map of light-map caustics: light-map (u, v), light-map slot + 1 and distance
    /// of everything but the map's own objects (src/technique/impostor/impostor_lightmap.rs).
    LightmapUv,
}

/// A cube map around a reference point: a distance impostor or a refractor map.
pub struct ImpostorMap {
    content: MapContent,
    /// A framebuffer per cube face.
    target: RenderTarget,
    pipeline: GraphicsPipeline,
    /// RGBA32F cube: radiance + distance (environment) or normal + distance (refractor).
    pub cube: Image,
    pub cube_id: ImageId,
    /// The separate R32F distance cube (`separate_distance`).
    pub distance: Option<(Image, ImageId)>,
    _depth: Image,
    depth_id: ImageId,
    /// Indices into `GpuScene::draws` rendered into the map.
    draws: Vec<usize>,
    /// The objects the map belongs to (whose centre is its reference point).
    objects: Vec<usize>,
    /// Scene bounds, for the far plane.
    bounds: (Vec3, f32),
    reference: Vec3,
    /// Bounding radius of the largest of `objects` (unit of `regenerate_distance`).
    radius: f32,
    update: ImpostorUpdate,
    regenerate_distance: f32,
    /// Per object, its light-mapped parts (`MapContent::LightmapUv`; see
    /// glsl/impostor/uv_map.frag): (first index within the object's indices, index count,
    /// light-map slot + 1, chart rows a and b with (u, v) = (a.p + a_w, b.p + b_w) for world
    /// position p). Empty: drawn whole with slot 0 (no light map).
    pub charts: Vec<Vec<UvChart>>,
    /// Render the map in the next frame.
    pending: bool,
    /// Render the map in the frame being recorded.
    regenerating: bool,
    generations: u32,
}

/// Which map: its pass name, its resources' label (the pass name, or with the object's name
/// per object), what it stores and whose it is.
pub struct MapDesc<'a> {
    pub name: &'static str,
    pub label: &'a str,
    pub content: MapContent,
    pub objects: Vec<usize>,
}

impl ImpostorMap {
    pub fn new(s: &mut Setup<'_>, desc: MapDesc<'_>, params: &ImpostorParams) -> GpuResult<Self> {
        let (ctx, scene, gpu, frame_layout) = (s.ctx, s.scene, s.gpu, s.frame_layout);
        let graph = &mut *s.graph;
        let MapDesc { name, label, content, objects } = desc;
        let size = params.resolution;
        let separate = content == MapContent::Environment && params.separate_distance;
        use vk::ImageUsageFlags as U;
        let cube_desc = |name: &str, format, view, usage| ImageDesc::square(name, format, size, 6, view, usage);
        let color_usage = U::COLOR_ATTACHMENT | U::SAMPLED | U::TRANSFER_SRC;
        let (cube, cube_id) = graph.image(ctx, &cube_desc(label, CUBE_FORMAT, ImageViewKind::Cube, color_usage))?;
        let distance = if separate {
            let desc = cube_desc(&format!("{label}_distance"), DISTANCE_FORMAT, ImageViewKind::Cube, color_usage);
            Some(graph.image(ctx, &desc)?)
        } else {
            None
        };
        let depth_desc =
            cube_desc(&format!("{label}_depth"), DEPTH_FORMAT, ImageViewKind::D2Array, U::DEPTH_STENCIL_ATTACHMENT);
        let (depth, depth_id) = graph.image(ctx, &depth_desc)?;
        // A framebuffer per face.
        let colors: Vec<&Image> = std::iter::once(&cube).chain(distance.as_ref().map(|(d, _)| d)).collect();
        let target = RenderTarget::layered(ctx, label, &colors, Some(&depth), true, 6)?;
        let fragment_shader = match (content, separate) {
            (MapContent::Refractor, _) => "impostor/refractor.frag",
            (MapContent::Environment, false) => "impostor/map.frag",
            (MapContent::Environment, true) => "impostor/map_separate.frag",
            (MapContent::LightmapUv, _) => "impostor/uv_map.frag",
        };
        let blend = vec![Blend::Off; colors.len()];
        let scene_specs = scene_specialization(scene);
        let pipeline = GraphicsPipeline::new(
            ctx,
            &GraphicsPipelineDesc {
                // Quads are one-sided and the reference point may sit on either side.
                blend: &blend,
                // The environment and lights of the shading in the environment maps.
                specialization: if content == MapContent::Environment { &scene_specs } else { &[] },
                ..GraphicsPipelineDesc::mesh(name, "impostor/map.vert", fragment_shader, DepthState::LESS)
            },
            &[frame_layout],
            std::mem::size_of::<MapPush>() as u32,
            &target.pass,
        )?;
        let draws = (0..scene.objects.len())
            .filter(|i| objects.contains(i) == (content == MapContent::Refractor))
            .filter(|&i| i < gpu.draws.len())
            .collect();
        let mut map = ImpostorMap {
            content,
            target,
            pipeline,
            cube,
            cube_id,
            distance,
            _depth: depth,
            depth_id,
            draws,
            objects,
            bounds: (gpu.bounds_center, gpu.bounds_radius),
            reference: Vec3::ZERO,
            radius: 0.0,
            update: params.update,
            regenerate_distance: params.regenerate_distance,
            charts: vec![Vec::new(); scene.objects.len()],
            pending: true,
            regenerating: false,
            generations: 0,
        };
        let centers: Vec<_> = (0..scene.objects.len()).map(|i| object_bounds(scene, i)).collect();
        map.reference = map.center_of(&centers);
        map.radius = map.objects.iter().map(|&i| centers[i].1).fold(0.0, f32::max);
        Ok(map)
    }

    pub fn center_of(&self, bounds: &[(Vec3, f32)]) -> Vec3 {
        let sum: Vec3 = self.objects.iter().map(|&i| bounds[i].0).sum();
        sum / self.objects.len().max(1) as f32
    }

    /// The map's reference point (the paper's o).
    pub fn reference(&self) -> Vec3 {
        self.reference
    }

    /// How many times the map has been rendered.
    pub fn generations(&self) -> u32 {
        self.generations
    }

    /// The objects' centres and radii changed (`bounds[i]` of object i): re-centre the map and
    /// render it again if they moved farther than `regenerate_distance` radii (§6). A refractor
    /// map moves with its object and is never rendered again.
    pub fn objects_moved(&mut self, bounds: &[(Vec3, f32)]) {
        let c = self.center_of(bounds);
        if self.content == MapContent::Refractor {
            // Not rendered yet: render it where the object now is.
            if self.generations == 0 {
                self.reference = c;
            }
            return;
        }
        if c.distance(self.reference) > self.regenerate_distance * self.radius {
            self.reference = c;
            self.pending = true;
        }
    }

    /// What the map shows changed in place (material values, animated vertices): an
    /// environment map, which holds radiance, is rendered again; a refractor map holds only
    /// its object's shape.
    pub fn contents_changed(&mut self) {
        if self.content == MapContent::Environment {
            self.pending = true;
        }
    }

    /// Decide whether this frame renders the map; call before recording.
    pub fn begin_frame(&mut self) {
        self.regenerating = self.pending || self.update == ImpostorUpdate::EveryFrame;
        self.pending = false;
        if self.regenerating {
            self.generations += 1;
        }
    }

    /// The distance cube (separate, or the alpha of the main cube) and its channel.
    fn distance_view(&self) -> (&Image, ImageId, u32) {
        match &self.distance {
            Some((image, id)) => (image, *id, 0),
            None => (&self.cube, self.cube_id, 3),
        }
    }

    /// Whether the frame being recorded renders this map.
    pub fn regenerating(&self) -> bool {
        self.regenerating
    }

    /// The images the map pass writes (and reads) when this map is rendered this frame.
    fn accesses<'f, 'g, 'a>(
        &self,
        mut pass: PassBuilder<'f, 'g, 'a>,
        shadow_atlas: Option<ImageId>,
    ) -> PassBuilder<'f, 'g, 'a> {
        if !self.regenerating {
            return pass;
        }
        pass = pass.write(self.cube_id, Access::ColorAttachment).write(self.depth_id, Access::DepthAttachment);
        if let Some((_, id)) = &self.distance {
            pass = pass.write(*id, Access::ColorAttachment);
        }
        if let (Some(atlas), MapContent::Environment) = (shadow_atlas, self.content) {
            pass = pass.read(atlas, Access::FragmentSampled);
        }
        pass
    }

    /// Render the six faces (if the map is due this frame).
    fn draw(&self, cmd: &Cmd, scene: &GpuScene, frame_set: DescriptorSet) {
        if !self.regenerating {
            return;
        }
        // Near and far planes bound the whole scene from the reference point; the depth only
        // orders surfaces, the stored distance is computed exactly per pixel.
        let far = (self.reference.distance(self.bounds.0) + self.bounds.1) * 1.01;
        let proj = Mat4::perspective_rh(std::f32::consts::FRAC_PI_2, 1.0, far * 1e-5, far);
        let views = cube_face_views(self.reference);
        let reference = self.reference.extend(1.0).to_array();
        let mut clears = vec![Clear::Color([0.0, 0.0, 0.0, NO_SURFACE])];
        if self.distance.is_some() {
            clears.push(Clear::Color([NO_SURFACE; 4]));
        }
        clears.push(Clear::Depth(1.0));
        for (face, view) in views.iter().enumerate() {
            cmd.in_target(&self.target, face, &clears, |cmd| {
                cmd.bind_graphics(&self.pipeline, &[frame_set]);
                cmd.bind_mesh_buffers(&scene.vertices, &scene.indices);
                for &i in &self.draws {
                    let d = &scene.draws[i];
                    let whole = [(0, d.index_count, 0, [0.0; 4], [0.0; 4])];
                    let parts = match self.charts.get(i) {
                        Some(c) if !c.is_empty() => c.as_slice(),
                        _ => &whole,
                    };
                    for &(first, count, slot, chart_u, chart_v) in parts {
                        let push = MapPush {
                            view_proj: (proj * *view).to_cols_array_2d(),
                            reference,
                            material: [d.material, slot, 0, 0],
                            chart_u,
                            chart_v,
                        };
                        cmd.push_graphics(&self.pipeline, &push);
                        cmd.draw_indexed(count, d.first_index + first, d.vertex_offset);
                    }
                }
            });
        }
    }

    /// Run glsl/impostor/probe.comp against this map: the shader's own `Hit()` with
    /// `iterations` steps (records: (x, _), (R, _), _ -> (hit, missed), (d, ratio, _, _), _),
    /// or the conductor Fresnel terms ((cos, ...), (eta, _), (k, _) -> (approx, _), (exact, _)).
    /// For tests; waits for the GPU.
    pub fn probe(
        &self,
        ctx: &Arc<GpuContext>,
        graph: &mut FrameGraph,
        fresnel: bool,
        iterations: u32,
        records: &[[[f32; 4]; 3]],
    ) -> GpuResult<Vec<[[f32; 4]; 3]>> {
        let mut data = records.to_vec();
        if data.is_empty() {
            return Ok(data);
        }
        let buffer = Buffer::storage(ctx, "impostor_probe_records", &data)?;
        let sampler = Sampler::new(ctx, "impostor_probe_linear", SamplerDesc::LINEAR_CLAMP)?;
        let (image, image_id, channel) = self.distance_view();
        let set = Bindings::new(vk::ShaderStageFlags::COMPUTE)
            .storage(BINDING_IMPOSTOR_PROBE, &buffer)
            .sampled(BINDING_IMPOSTOR_DISTANCE, image, &sampler)
            .read(image_id)
            .build(ctx, "impostor_probe")?;
        let pipeline = ComputePipeline::new(
            ctx,
            "impostor_probe",
            "impostor/probe.comp",
            &[set.layout()],
            std::mem::size_of::<ImpostorProbePush>() as u32,
            &[("ITERATIONS", Spec::U32(iterations)), ("DISTANCE_CHANNEL", Spec::U32(channel))],
        )?;
        let buffer_id = graph.register_buffer(&buffer);
        let mode = if fresnel { IMPOSTOR_PROBE_FRESNEL } else { IMPOSTOR_PROBE_HIT };
        let push = ImpostorProbePush {
            reference: self.reference.extend(0.0).to_array(),
            info: [data.len() as u32, mode, 0, 0],
        };
        let groups = (data.len() as u32).div_ceil(WORKGROUP_2D * WORKGROUP_2D);
        ctx.one_shot(|cmd| {
            let mut frame = graph.frame();
            frame.pass("impostor_probe").uses(&set).write(buffer_id, Access::ComputeWrite).record(|cmd| {
                cmd.compute(&pipeline, &[set.set()], &push, [groups, 1, 1]);
            });
            frame.execute(cmd, None);
            graph.access_now(cmd, &[], &[(buffer_id, Access::HostRead)]);
        })?;
        ctx.wait_idle()?;
        data.copy_from_slice(bytemuck::cast_slice(buffer.read()));
        Ok(data)
    }
}

/// One frame-graph pass rendering every map of `maps` that is due this frame (§6: a map whose
/// objects did not move far enough keeps the earlier frame's content; with none due the pass
/// records nothing).
pub(crate) fn record_maps<'a>(
    frame: &mut Frame<'_, 'a>,
    name: &str,
    maps: Vec<&'a ImpostorMap>,
    scene: &'a GpuScene,
    frame_set: DescriptorSet,
    shadow_atlas: Option<ImageId>,
) {
    let mut pass = frame.pass(name);
    for m in &maps {
        pass = m.accesses(pass, shadow_atlas);
    }
    pass.record(move |cmd| {
        for m in maps {
            m.draw(cmd, scene, frame_set);
        }
    });
}

/// A full-screen pass shading the specular pixels of the G-buffer with the impostors: one
/// draw per (environment map, refractor map) instance, each with its own descriptor set.
struct ShadePass {
    name: &'static str,
    target: RenderTarget,
    /// One set per instance.
    sets: BoundSet,
    /// Set 2: the exact tracer's buffers, for the oracle (`render.impostor.oracle`).
    tracer: Option<BoundSet>,
    pipeline: GraphicsPipeline,
    _linear: Sampler,
}

impl ShadePass {
    /// `oracle`: the exact tracer, bound in set 2 of `fragment_shader`'s oracle variant
    /// (`impostor/reflect.frag` -> `impostor/reflect_oracle.frag`).
    fn new(
        s: &Setup<'_>,
        name: &'static str,
        fragment_shader: &str,
        params: &ImpostorParams,
        instances: &[(&ImpostorMap, Option<&ImpostorMap>)],
        oracle: Option<&Oracle>,
    ) -> GpuResult<Self> {
        let (ctx, targets) = (s.ctx, s.targets);
        let scene_specs = scene_specialization(s.scene);
        let target = RenderTarget::new(ctx, name, &[&targets.hdr], None, false)?;
        // Cube maps are filtered: bilinear distances follow planar walls between texels
        // (§2.1 assumes the surface planar between samples); the G-buffer is fetched per texel.
        let linear = Sampler::new(ctx, &format!("{name}_linear"), SamplerDesc::LINEAR_CLAMP)?;
        // All instances share one distance channel: they come from the same parameters.
        let mut channel = 3;
        let sets = instances.iter().map(|(env, refractor)| {
            let (dist_image, dist_id, c) = env.distance_view();
            channel = c;
            let mut b = targets
                .gbuffer(Bindings::new(vk::ShaderStageFlags::FRAGMENT), s.nearest, true)
                .sampled(BINDING_IMPOSTOR_RADIANCE, &env.cube, &linear)
                .read(env.cube_id)
                .sampled(BINDING_IMPOSTOR_DISTANCE, dist_image, &linear);
            if dist_id != env.cube_id {
                b = b.read(dist_id);
            }
            if let Some(r) = refractor {
                b = b.sampled(BINDING_IMPOSTOR_REFRACTOR, &r.cube, &linear).read(r.cube_id);
            }
            b
        });
        let sets = Bindings::build_each(ctx, name, sets.collect())?;
        let tracer = match oracle {
            Some(o) => Some(o.set(ctx, s.gpu, vk::ShaderStageFlags::FRAGMENT, &format!("{name}_tracer"))?),
            None => None,
        };
        let mut layouts = vec![s.frame_layout, sets.layout()];
        layouts.extend(tracer.as_ref().map(|t| t.layout()));
        let fragment_shader = match oracle {
            Some(_) => fragment_shader.replace(".frag", "_oracle.frag"),
            None => fragment_shader.to_string(),
        };
        let pipeline = GraphicsPipeline::new(
            ctx,
            &GraphicsPipelineDesc {
                // glsl/impostor/shade_common.glsl.
                specialization: &[
                    ("ITERATIONS", Spec::U32(params.iterations)),
                    ("DISTANCE_CHANNEL", Spec::U32(channel)),
                    ("FRESNEL_EXACT", Spec::U32(u32::from(params.fresnel == ImpostorFresnel::Exact))),
                    scene_specs[0],
                    scene_specs[1],
                    scene_specs[2],
                ],
                ..GraphicsPipelineDesc::fullscreen(name, &fragment_shader)
            },
            &layouts,
            std::mem::size_of::<ShadePush>() as u32,
            &target.pass,
        )?;
        Ok(ShadePass { name, target, sets, tracer, pipeline, _linear: linear })
    }

    /// One full-screen draw per instance (`pushes[i]` with `sets[i]`).
    fn record<'a>(
        &'a self,
        frame: &mut Frame<'_, 'a>,
        targets: &Targets,
        frame_set: DescriptorSet,
        environment: ImageId,
        pushes: Vec<ShadePush>,
    ) {
        let mut pass = frame.pass(self.name).uses(&self.sets).read(environment, Access::FragmentSampled);
        if let Some(t) = &self.tracer {
            pass = pass.uses(t);
        }
        let tracer = self.tracer.as_ref().map(|t| t.set());
        pass.write(targets.hdr_id, Access::ColorAttachment).record(move |cmd| {
            // Keeps the deferred result and overwrites only the pixels of its materials (and,
            // per object, of the instance's object).
            cmd.in_target(&self.target, 0, &[Clear::None], |cmd| {
                for (set, push) in self.sets.sets().iter().zip(&pushes) {
                    let mut sets = vec![frame_set, *set];
                    sets.extend(tracer);
                    cmd.bind_graphics(&self.pipeline, &sets);
                    cmd.push_graphics(&self.pipeline, push);
                    cmd.draw(3, 1);
                }
            });
        });
    }
}

/// The exact tracer of `render.impostor.oracle = "hit"`; none for the paper's technique.
fn oracle(s: &mut Setup<'_>, params: &ImpostorParams) -> Result<Option<Oracle>, RenderError> {
    match params.oracle {
        ImpostorOracle::None => Ok(None),
        ImpostorOracle::Hit => Ok(Some(Oracle::new(s)?)),
    }
}

fn objects_where(scene: &Scene, pred: impl Fn(&Material) -> bool) -> Vec<usize> {
    (0..scene.objects.len()).filter(|&i| pred(&scene.materials[scene.objects[i].material])).collect()
}

/// The object groups that get a map each: all of `objects` together (`"shared"`), or one group
/// per object (`"per_object"`).
fn map_groups(params: &ImpostorParams, objects: Vec<usize>) -> Vec<Vec<usize>> {
    match params.maps {
        ImpostorMaps::Shared => vec![objects],
        ImpostorMaps::PerObject => objects.into_iter().map(|i| vec![i]).collect(),
    }
}

/// What a map's label adds to its pass name: nothing when shared, the object's name per object.
fn map_suffix(scene: &Scene, params: &ImpostorParams, objects: &[usize]) -> String {
    match params.maps {
        ImpostorMaps::Shared => String::new(),
        ImpostorMaps::PerObject => format!("_{}", scene.objects[objects[0]].name),
    }
}

/// The shading push constant's object: the group's only object per object, all when shared.
fn shaded_object(params: &ImpostorParams, objects: &[usize]) -> u32 {
    match (params.maps, objects) {
        (ImpostorMaps::PerObject, [i]) => *i as u32,
        _ => ALL_OBJECTS,
    }
}

/// `render.reflection = "impostor"`: localized reflections of mirrors and conductors (§3).
pub struct ImpostorReflection {
    /// One shared map, or one per mirror/conductor object (`render.impostor.maps`).
    pub maps: Vec<ImpostorMap>,
    shade: ShadePass,
    pub params: ImpostorParams,
    /// The exact tracer `render.impostor.oracle = "hit"` reads.
    oracle: Option<Oracle>,
}

impl ImpostorReflection {
    pub fn new(s: &mut Setup<'_>) -> Result<Self, RenderError> {
        let params = impostor_params(s)?;
        let oracle = oracle(s, &params)?;
        let metals = objects_where(s.scene, |m| matches!(m, Material::Mirror { .. } | Material::Conductor { .. }));
        let mut maps = Vec::new();
        for group in map_groups(&params, metals) {
            let label = format!("{REFLECTION_IMPOSTOR_MAP}{}", map_suffix(s.scene, &params, &group));
            let desc = MapDesc {
                name: REFLECTION_IMPOSTOR_MAP,
                label: &label,
                content: MapContent::Environment,
                objects: group,
            };
            maps.push(ImpostorMap::new(s, desc, &params)?);
        }
        let instances: Vec<_> = maps.iter().map(|m| (m, None)).collect();
        let shade =
            ShadePass::new(s, REFLECTION_IMPOSTOR, "impostor/reflect.frag", &params, &instances, oracle.as_ref())?;
        Ok(ImpostorReflection { maps, shade, params, oracle })
    }

    /// Objects moved (`bounds[i]`: object i's centre and radius): each map decides (§6).
    pub fn objects_moved(&mut self, bounds: &[(Vec3, f32)]) {
        for m in &mut self.maps {
            m.objects_moved(bounds);
        }
    }

    pub fn begin_frame(&mut self) {
        for m in &mut self.maps {
            m.begin_frame();
        }
    }

    pub fn contents_changed(&mut self) {
        for m in &mut self.maps {
            m.contents_changed();
        }
    }

    pub fn record<'a>(
        &'a self,
        frame: &mut Frame<'_, 'a>,
        scene: &'a GpuScene,
        targets: &Targets,
        frame_set: DescriptorSet,
        shadow_atlas: Option<ImageId>,
    ) {
        record_maps(frame, REFLECTION_IMPOSTOR_MAP, self.maps.iter().collect(), scene, frame_set, shadow_atlas);
        let pushes = self
            .maps
            .iter()
            .map(|m| ShadePush {
                env_reference: m.reference.extend(1.0).to_array(),
                refractor_center: [0.0; 4],
                object: [shaded_object(&self.params, &m.objects), 0, 0, 0],
            })
            .collect();
        self.shade.record(frame, targets, frame_set, scene.environment_id, pushes);
    }
}

/// One refractor (or all of them, shared): its environment impostor, its refractor map, and
/// where the refractors' centre is now (the refractor map moves with them).
pub struct RefractionInstance {
    pub map: ImpostorMap,
    pub refractor: ImpostorMap,
    refractor_center: Vec3,
}

/// `render.refraction = "impostor"`: double refraction through a refractor map (§4).
pub struct ImpostorRefraction {
    /// One shared instance, or one per dielectric object (`render.impostor.maps`).
    pub instances: Vec<RefractionInstance>,
    shade: ShadePass,
    pub params: ImpostorParams,
    /// The exact tracer `render.impostor.oracle = "hit"` reads.
    oracle: Option<Oracle>,
}

impl ImpostorRefraction {
    pub fn new(s: &mut Setup<'_>) -> Result<Self, RenderError> {
        let params = impostor_params(s)?;
        let oracle = oracle(s, &params)?;
        let glass = objects_where(s.scene, |m| matches!(m, Material::Dielectric { .. }));
        let mut instances = Vec::new();
        for group in map_groups(&params, glass) {
            let suffix = map_suffix(s.scene, &params, &group);
            let label = format!("{REFRACTION_IMPOSTOR_MAP}{suffix}");
            let objects = group.clone();
            let desc =
                MapDesc { name: REFRACTION_IMPOSTOR_MAP, label: &label, content: MapContent::Environment, objects };
            let map = ImpostorMap::new(s, desc, &params)?;
            let label = format!("{REFRACTION_IMPOSTOR_REFRACTOR_MAP}{suffix}");
            let (name, content) = (REFRACTION_IMPOSTOR_REFRACTOR_MAP, MapContent::Refractor);
            let refractor = ImpostorMap::new(s, MapDesc { name, label: &label, content, objects: group }, &params)?;
            let refractor_center = refractor.reference;
            instances.push(RefractionInstance { map, refractor, refractor_center });
        }
        let pairs: Vec<_> = instances.iter().map(|i| (&i.map, Some(&i.refractor))).collect();
        let shade = ShadePass::new(s, REFRACTION_IMPOSTOR, "impostor/refract.frag", &params, &pairs, oracle.as_ref())?;
        Ok(ImpostorRefraction { instances, shade, params, oracle })
    }

    pub fn objects_moved(&mut self, bounds: &[(Vec3, f32)]) {
        for i in &mut self.instances {
            i.map.objects_moved(bounds);
            i.refractor.objects_moved(bounds);
            i.refractor_center = i.refractor.center_of(bounds);
        }
    }

    pub fn contents_changed(&mut self) {
        for i in &mut self.instances {
            i.map.contents_changed();
            i.refractor.contents_changed();
        }
    }

    pub fn begin_frame(&mut self) {
        for i in &mut self.instances {
            i.map.begin_frame();
            i.refractor.begin_frame();
        }
    }

    pub fn record<'a>(
        &'a self,
        frame: &mut Frame<'_, 'a>,
        scene: &'a GpuScene,
        targets: &Targets,
        frame_set: DescriptorSet,
        shadow_atlas: Option<ImageId>,
    ) {
        let envs = self.instances.iter().map(|i| &i.map).collect();
        record_maps(frame, REFRACTION_IMPOSTOR_MAP, envs, scene, frame_set, shadow_atlas);
        let refractors = self.instances.iter().map(|i| &i.refractor).collect();
        record_maps(frame, REFRACTION_IMPOSTOR_REFRACTOR_MAP, refractors, scene, frame_set, None);
        let pushes = self
            .instances
            .iter()
            .map(|i| ShadePush {
                env_reference: i.map.reference.extend(1.0).to_array(),
                refractor_center: i.refractor_center.extend(1.0).to_array(),
                object: [shaded_object(&self.params, &i.map.objects), 0, 0, 0],
            })
            .collect();
        self.shade.record(frame, targets, frame_set, scene.environment_id, pushes);
    }
}

#[cfg(test)]
mod tests {
    use super::{object_bounds, tight_object_bounds};

    /// The tight sphere holds every vertex, never exceeds the box's, and on bunny_env's bunny
    /// is the farthest vertex's distance (1.34 against the box's half-diagonal, 1.59).
    #[test]
    fn the_tight_sphere_holds_every_vertex_within_the_boxs() {
        let path = crate::scene::benchmark_scene_path("bunny_env");
        let scene = crate::scene::load(&path, &[]).unwrap();
        let (centre, radius) = tight_object_bounds(&scene, 0);
        let (box_centre, box_radius) = object_bounds(&scene, 0);
        assert_eq!(centre, box_centre);
        let farthest = scene.objects[0].mesh.positions.iter().map(|p| p.distance(centre)).fold(0.0, f32::max);
        assert_eq!(radius, farthest);
        assert!(radius < 0.9 * box_radius, "{radius} against the box's {box_radius}");
        // A sphere is its own bound.
        let ball = crate::scene::load(&crate::scene::benchmark_scene_path("sphere_env"), &[]).unwrap();
        assert_eq!(tight_object_bounds(&ball, 0), object_bounds(&ball, 0));
    }
}
