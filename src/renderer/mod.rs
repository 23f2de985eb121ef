//! The renderer: turns a [`Scene`] into GPU data, creates exactly the passes the scene
//! needs ([`plan`]), records them through the frame graph each frame, and reads back images
//! and per-pass GPU timings. Headless; the demo window shares it and only swaps the final
//! target.
pub mod plan;
mod present;
mod update;

pub use present::{OverlayDraw, WindowTarget, OVERLAY, PRESENT_BLIT};
pub use update::{technique_passes, Update};

use std::sync::Arc;

use glam::{Mat4, Vec3};

use crate::gpu::{
    vk, Access, Buffer, CommandPool, GpuContext, Image, MemoryKinds, MemoryLocation, PassCounts, PipelineStatsPool,
    Sampler, SamplerDesc, SubmitSync, TimestampPool, TimestampQuery,
};
use crate::graph::{Bindings, BoundSet, Frame, FrameGraph, ImageId};
use crate::scene::techniques::{Flux, PhotonBufferParams};
use crate::scene::{Camera, Scene};
use crate::technique::baseline::shadow_map::FAR_DISTANCE;
use crate::technique::baseline::tonemap::{AdaptiveStats, TonemapPass};
use crate::technique::caustics::caustics_map::CausticsMapPass;
use crate::technique::caustics::photon_buffer::{PhotonBufferPass, PhotonCaustics};
use crate::technique::eikonal::eikonal_view::EikonalPass;
use crate::technique::impostor::distance_impostor::{
    object_bounds, object_box, tight_object_bounds, ImpostorMap, ImpostorReflection, ImpostorRefraction,
};
use crate::technique::impostor::impostor_lightmap::ImpostorLightmap;
use crate::technique::refraction::refractor_layers::DebugTarget;
use crate::technique::{Cache, FrameInputs, Recipe, Setup, Technique, TECHNIQUES};
use crate::{
    BINDING_CAUSTIC_2D, BINDING_CAUSTIC_CUBE, BINDING_CAUSTIC_RECEIVERS_2D, BINDING_CAUSTIC_RECEIVERS_CUBE,
    BINDING_ENVIRONMENT, BINDING_FRAME, BINDING_MATERIALS, BINDING_PHOTON_CAUSTICS, BINDING_PHOTON_RECTS,
    BINDING_SHADOW_2D, BINDING_SHADOW_CUBE,
};

use crate::frame::gpu_scene::GpuScene;
use crate::frame::heightfield::HeightfieldAnimation;
use crate::frame::targets::{CausticAtlas, Targets};
pub use crate::frame::RenderError;
use crate::shader_structs::{FrameUniforms, Vertex};
use plan::PlannedPass;

/// Frames the CPU may record ahead of the GPU; each has its own command buffer, fence,
/// uniform buffer, descriptor set and timestamp pool.
pub const FRAMES_IN_FLIGHT: usize = 2;

/// Timestamp pairs reserved for passes a caller appends to a frame
/// ([`Renderer::render_frame_with`]: the demo window's blit and overlay).
pub const EXTRA_TIMED_PASSES: usize = 4;

/// The tone-mapped image a caller's extra passes read (the demo copies it to the window).
pub struct FinalImage<'a> {
    pub ldr: &'a Image,
    pub ldr_id: ImageId,
}

/// GPU time of one pass in one frame, in milliseconds from the frame's first timestamp.
#[derive(Clone, Debug, serde::Serialize)]
pub struct PassTime {
    pub name: String,
    pub start_ms: f64,
    pub end_ms: f64,
    /// Its pipeline statistics, when they are counted ([`Renderer::count_pipeline_stats`]).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub counts: Option<PassCounts>,
    /// The pass recorded no device work this frame: a cached result with nothing due (a
    /// distance impostor's map between regenerations), its time only its timestamps' own.
    #[serde(skip_serializing_if = "std::ops::Not::not")]
    pub idle: bool,
}

impl PassTime {
    pub fn duration_ms(&self) -> f64 {
        self.end_ms - self.start_ms
    }
}

#[derive(Clone, Debug, serde::Serialize)]
pub struct FrameTiming {
    pub frame: u64,
    /// The frame's first timestamp on the device clock, in ms (for laying out traces).
    pub gpu_start_ms: f64,
    pub passes: Vec<PassTime>,
}

impl FrameTiming {
    /// Frame time = last end - first start (../shared/DESIGN.md, rule 6).
    pub fn total_ms(&self) -> f64 {
        let start = self.passes.iter().map(|p| p.start_ms).fold(f64::INFINITY, f64::min);
        let end = self.passes.iter().map(|p| p.end_ms).fold(f64::NEG_INFINITY, f64::max);
        if self.passes.is_empty() {
            0.0
        } else {
            end - start
        }
    }
}

pub struct Renderer {
    // Field order matters for drop: techniques and GPU data before the context they came from.
    /// One slot per entry of [`TECHNIQUES`]; `None` where the scene plans none of its passes.
    techniques: Vec<Option<Box<dyn Technique>>>,
    /// Hu & Qin 2007 §3's caustic textures and rectangles (a stand-in without photon_buffer),
    /// bound in the frame set.
    photon_caustics: PhotonCaustics,
    /// Set 0 of every pass, one per frame in flight.
    frame_sets: BoundSet,
    frame_buffers: Vec<Buffer>,
    _samplers: Vec<Sampler>,
    scene: GpuScene,
    targets: Targets,
    timestamps: Vec<TimestampPool>,
    /// One pipeline-statistics pool per frame in flight; empty unless counting.
    pipeline_stats: Vec<PipelineStatsPool>,
    /// Device memory each technique created, and the shared resources' ("frame").
    memory: Vec<TechniqueMemory>,
    commands: CommandPool,
    graph: FrameGraph,
    recipe: Recipe,
    /// What [`Renderer::update`] compares a changed scene against: the shared resources'
    /// fingerprint, and each technique's (`None`: not in the recipe).
    shared_fingerprint: u64,
    technique_fingerprints: Vec<Option<u64>>,
    /// What the caustic atlas and the photon-buffer textures were made for.
    caustic_size: Option<u32>,
    photon_params: Option<PhotonBufferParams>,
    /// The shaders each technique's pipelines were created from (for the hot reload).
    technique_shaders: Vec<Vec<String>>,
    /// [`crate::technique::placement_hash`] of the scene the vertices and lights hold (none
    /// after an object was dragged).
    placement: Option<u64>,
    /// What techniques keep across their re-creation (the eikonal light simulation).
    cache: Cache,
    /// The heightfields' animation on the GPU, and the time the next frame moves them to.
    animation: Option<HeightfieldAnimation>,
    animation_time: Option<f32>,
    /// The vertices were animated since the last update.
    animated: bool,
    /// `render.update = "every_frame"`: what techniques keep is rendered in every frame.
    every_frame: bool,
    /// How long work that spans frames (the eikonal light simulation) may run before each
    /// frame; None: all of it before the first frame that needs it.
    work_budget: Option<std::time::Duration>,
    /// Every object's vertex range and current (centre, bounding radius), for moving objects.
    objects: Vec<ObjectState>,
    /// The objects' (centre, tight radius), copied from `objects` for each frame's inputs
    /// ([`FrameInputs::object_bounds`]).
    bounds: Vec<(Vec3, f32)>,
    /// The same for [`FrameInputs::object_boxes`].
    boxes: Vec<(Vec3, Vec3)>,
    uniforms: FrameUniforms,
    /// (frame index, queries) of each slot's submitted but not yet read frame.
    pending: Vec<Option<(u64, Vec<TimestampQuery>)>>,
    completed: Vec<FrameTiming>,
    frame_index: u64,
    /// Seconds since the last frame for the adaptive tone map's temporal adaptation; `None`:
    /// converged (headless). The first frame of a renderer is always converged.
    tonemap_dt: Option<f32>,
    /// What the adaptive tone map derived in the last completed frame.
    tonemap_stats: Option<AdaptiveStats>,
    ctx: Arc<GpuContext>,
}

/// Device memory that one technique's creation allocated (or, under the name "frame", the
/// resources every technique shares: the scene's buffers, the targets, the atlases).
#[derive(Clone, Debug, serde::Serialize)]
pub struct TechniqueMemory {
    /// The technique's key in [`TECHNIQUES`] (`refraction = "wyman"`, `gbuffer`, ...).
    pub technique: String,
    #[serde(flatten)]
    pub bytes: MemoryKinds,
}

/// Where an object's vertices are in the scene's vertex buffer, and where the object is now.
struct ObjectState {
    name: String,
    first_vertex: usize,
    vertex_count: usize,
    bounds: (Vec3, f32),
    /// The radius about `bounds`' centre that holds every vertex ([`tight_object_bounds`]):
    /// the frame's [`FrameInputs::object_bounds`].
    tight_radius: f32,
    /// Half the extents of its box about `bounds`' centre ([`object_box`]).
    half_extent: Vec3,
}

/// Which effect's distance impostor [`Renderer::impostor_map`] and
/// [`Renderer::probe_impostor`] address.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ImpostorEffect {
    /// The environment impostor of `render.reflection = "impostor"`.
    Reflection,
    /// The environment impostor of `render.refraction = "impostor"`.
    Refraction,
    /// The refractor map of `render.refraction = "impostor"`.
    Refractor,
}

/// Camera projection: reversed-Z with an infinite far plane (depth 1 at the near plane,
/// 0 at infinity) for uniform precision over scene scales of 1e-3 to 1e4, y flipped for
/// Vulkan's downward y so that pixel row 0 is the top of the image (SCENES.md).
pub fn camera_projection(vfov_deg: f32, aspect: f32, near: f32) -> Mat4 {
    let mut p = Mat4::perspective_infinite_reverse_rh(vfov_deg.to_radians(), aspect, near);
    p.y_axis.y = -p.y_axis.y;
    p
}

impl Renderer {
    pub fn new(ctx: &Arc<GpuContext>, scene: &Scene) -> Result<Renderer, RenderError> {
        let recipe = crate::technique::recipe(scene);
        let plan = &recipe.passes;
        let memory_start = ctx.memory_kinds();
        let mut graph = FrameGraph::new();
        let shadow_size = scene.render.shadow_map_size;
        let shadowed = plan::has(plan, crate::technique::baseline::shadow_map::SHADOW_MAP);
        let gpu_scene = GpuScene::new(ctx, scene, &mut graph, shadow_size)?;
        // The frame set binds the caustic atlas and the photon-buffer textures whether or not
        // a caustic technique writes them; their sizes follow the technique's parameters.
        let caustic_size = update::caustic_size(scene, &recipe)?;
        let photon_params = update::photon_params(scene, &recipe)?;
        let photon_caustics = PhotonCaustics::new(ctx, &mut graph, scene, photon_params.as_ref())?;
        let targets = Targets::new(
            ctx,
            &mut graph,
            scene.camera.width,
            scene.camera.height,
            if shadowed { scene.lights.len() as u32 } else { 0 },
            shadow_size,
            caustic_size,
        )?;

        let nearest = Sampler::new(ctx, "nearest_clamp", SamplerDesc::NEAREST_CLAMP)?;
        let latlong = Sampler::new(ctx, "latlong", SamplerDesc::LATLONG)?;
        let frame_buffers = (0..FRAMES_IN_FLIGHT)
            .map(|i| {
                let size = std::mem::size_of::<FrameUniforms>() as u64;
                let name = format!("frame_uniforms_{i}");
                Buffer::new(ctx, &name, size, vk::BufferUsageFlags::UNIFORM_BUFFER, MemoryLocation::CpuToGpu)
            })
            .collect::<Result<Vec<_>, _>>()?;
        let frame_set = |ubo| {
            let set = Bindings::new(FRAME_STAGES)
                .uniform(BINDING_FRAME, ubo)
                .uniform(BINDING_MATERIALS, &gpu_scene.materials)
                .sampled(BINDING_ENVIRONMENT, &gpu_scene.environment, &latlong);
            let set = bind_atlas(set, [BINDING_SHADOW_CUBE, BINDING_SHADOW_2D], &targets.shadow_atlas, &nearest);
            let set = bind_caustic_atlas(set, &targets.caustic, &nearest);
            bind_photon_caustics(set, &photon_caustics, &nearest)
        };
        let frame_sets = Bindings::build_each(ctx, "frame", frame_buffers.iter().map(frame_set).collect())?;
        // The atlases are bound even when no pass writes them: give them defined contents
        // ("nothing occludes", "no caustic light") and the layout the shaders expect.
        clear_atlas(ctx, &mut graph, &targets.shadow_atlas, targets.shadow_atlas_id, FAR_DISTANCE)?;
        clear_caustic_atlas(ctx, &mut graph, &targets.caustic)?;
        let objects = (0..scene.objects.len())
            .map(|i| ObjectState {
                name: scene.objects[i].name.clone(),
                first_vertex: gpu_scene.draws[i].vertex_offset as usize,
                vertex_count: scene.objects[i].mesh.positions.len(),
                bounds: object_bounds(scene, i),
                tight_radius: tight_object_bounds(scene, i).1,
                half_extent: object_box(scene, i).1,
            })
            .collect();
        let mut cache = Cache::default();
        cache.begin();
        let mut setup = Setup {
            ctx,
            scene,
            gpu: &gpu_scene,
            graph: &mut graph,
            frame_layout: frame_sets.layout(),
            targets: &targets,
            nearest: &nearest,
            photon_caustics: &photon_caustics,
            plan,
            slots: FRAMES_IN_FLIGHT,
            cache: &mut cache,
        };
        let mut techniques = Vec::with_capacity(TECHNIQUES.len());
        let mut technique_shaders = Vec::with_capacity(TECHNIQUES.len());
        let shared = ctx.memory_kinds().since(&memory_start);
        let mut memory = vec![TechniqueMemory { technique: "frame".into(), bytes: shared }];
        for (i, t) in TECHNIQUES.iter().enumerate() {
            ctx.take_shader_log();
            let before = ctx.memory_kinds();
            techniques.push(if recipe.uses(i) { Some((t.create)(&mut setup)?) } else { None });
            if recipe.uses(i) {
                memory.push(TechniqueMemory { technique: t.key.into(), bytes: ctx.memory_kinds().since(&before) });
            }
            technique_shaders.push(ctx.take_shader_log());
        }
        cache.end();

        let mut uniforms = FrameUniforms {
            env_sh: gpu_scene.env_sh,
            info: [gpu_scene.lights.len() as u32, 0, 0, 0],
            ..bytemuck::Zeroable::zeroed()
        };
        set_camera_uniforms(&mut uniforms, &scene.camera, scene.render.exposure, &gpu_scene);
        for (i, l) in gpu_scene.lights.iter().enumerate() {
            uniforms.lights[i] = *l;
        }

        let mut timestamps = Vec::new();
        for i in 0..FRAMES_IN_FLIGHT {
            let pairs = plan.len() + EXTRA_TIMED_PASSES;
            timestamps.push(TimestampPool::new(ctx, &format!("timestamps_{i}"), 2 * pairs as u32)?);
        }
        let shared_fingerprint = update::shared_fingerprint(scene, &recipe);
        let placement = crate::technique::placement_hash(scene);
        let technique_fingerprints =
            (0..TECHNIQUES.len()).map(|i| update::technique_fingerprint(scene, &recipe, i, placement)).collect();
        let animation = HeightfieldAnimation::new(ctx, scene, &gpu_scene)?;
        Ok(Renderer {
            techniques,
            photon_caustics,
            frame_sets,
            frame_buffers,
            _samplers: vec![nearest, latlong],
            scene: gpu_scene,
            targets,
            timestamps,
            pipeline_stats: Vec::new(),
            memory,
            commands: CommandPool::new(ctx, FRAMES_IN_FLIGHT as u32)?,
            graph,
            recipe,
            shared_fingerprint,
            technique_fingerprints,
            caustic_size,
            photon_params,
            technique_shaders,
            placement: Some(placement),
            cache,
            animation,
            animation_time: None,
            animated: false,
            every_frame: scene.render.update == "every_frame",
            work_budget: None,
            objects,
            bounds: Vec::new(),
            boxes: Vec::new(),
            uniforms,
            pending: vec![None; FRAMES_IN_FLIGHT],
            completed: Vec::new(),
            frame_index: 0,
            tonemap_dt: None,
            tonemap_stats: None,
            ctx: ctx.clone(),
        })
    }

    /// Move the heightfields (the water's surface) to `time` on the GPU with the next frame,
    /// without a scene update (see [`HeightfieldAnimation`]). False: the scene has none.
    pub fn animate(&mut self, time: f32) -> bool {
        if self.animation.is_none() {
            return false;
        }
        self.animation_time = Some(time);
        self.animated = true;
        for t in self.techniques.iter_mut().flatten() {
            t.contents_changed();
        }
        // The vertices no longer hold the loaded scene's placement: the next update rewrites them.
        self.placement = None;
        true
    }

    /// Whether [`Renderer::animate`] moved the vertices since the last update.
    pub fn animated(&self) -> bool {
        self.animated
    }

    /// The created technique of type `T`, if the scene planned it.
    pub fn technique<T: Technique>(&self) -> Option<&T> {
        technique(&self.techniques)
    }

    /// Every created technique's debug targets.
    fn debug_target_list(&self) -> impl Iterator<Item = &DebugTarget> {
        debug_targets(&self.techniques)
    }

    pub fn context(&self) -> &Arc<GpuContext> {
        &self.ctx
    }

    /// The eikonal light simulation's steps, patch counts and time (None without one).
    pub fn light_stats(&self) -> Option<&crate::technique::eikonal::eikonal_light::LightStats> {
        self.technique::<EikonalPass>().and_then(|p| p.light_stats())
    }

    /// What the techniques computed outside the frame's passes and keep until a change
    /// ([`crate::technique::Technique::once_costs`]).
    pub fn once_costs(&self) -> Vec<crate::technique::OnceCost> {
        let mut costs: Vec<crate::technique::OnceCost> = Vec::new();
        // Techniques sharing a cached result (raytrace's two effects, its geometry) name it
        // alike: it was paid once.
        for c in self.techniques.iter().flatten().flat_map(|t| t.once_costs()) {
            if !costs.iter().any(|k| k.name == c.name) {
                costs.push(c);
            }
        }
        costs
    }

    /// The passes this renderer records, in order, with the reason for each.
    pub fn plan(&self) -> &[PlannedPass] {
        &self.recipe.passes
    }

    pub fn width(&self) -> u32 {
        self.targets.width
    }

    pub fn height(&self) -> u32 {
        self.targets.height
    }

    /// Test-only fault injection: stop emitting barriers for the target named `name`
    /// (see [`FrameGraph::skip_barriers_for_tests`]).
    #[doc(hidden)]
    pub fn skip_barriers_for_tests(&mut self, name: &str) {
        let t = &self.targets;
        let ids =
            [t.gbuf_normal_id, t.gbuf_albedo_id, t.depth_id, t.hdr_id, t.ldr_id, t.shadow_atlas_id, t.shadow_depth_id];
        for id in ids {
            if self.graph.image_name(id) == name {
                self.graph.skip_barriers_for_tests(id);
            }
        }
    }

    /// Let the adaptive tone map adapt over time: `Some(seconds since the last frame)` (the
    /// demo window), or `None` for the converged state of every headless render.
    pub fn set_tonemap_time_step(&mut self, dt: Option<f32>) {
        self.tonemap_dt = dt;
    }

    /// L_avg, the adapted luminance, the key and L_white of the last completed frame (the
    /// adaptive tone map only).
    pub fn tonemap_stats(&self) -> Option<AdaptiveStats> {
        self.tonemap_stats
    }

    fn collect_slot(&mut self, slot: usize) -> Result<(), RenderError> {
        if let Some((frame, queries)) = self.pending[slot].take() {
            if let Some(s) = self.technique::<TonemapPass>().and_then(|t| t.stats(slot)) {
                self.tonemap_stats = Some(s);
            }
            let pool = &self.timestamps[slot];
            let last = queries.iter().map(|q| q.end + 1).max().unwrap_or(0);
            let counts = match self.pipeline_stats.get(slot) {
                Some(stats) => {
                    let n = queries.iter().map(|q| q.pass + 1).max().unwrap_or(0).min(stats.capacity());
                    stats.read(n)?
                }
                None => None,
            };
            if let Some(ticks) = pool.read_ticks(last)? {
                let origin = queries.iter().map(|q| ticks[q.start as usize]).min().unwrap_or(0);
                let passes = queries
                    .iter()
                    .map(|q| PassTime {
                        name: q.name.clone(),
                        start_ms: pool.ticks_to_ms(origin, ticks[q.start as usize]),
                        end_ms: pool.ticks_to_ms(origin, ticks[q.end as usize]),
                        counts: counts.as_ref().and_then(|c| c.get(q.pass as usize).copied()),
                        idle: !q.ran,
                    })
                    .collect();
                self.completed.push(FrameTiming { frame, gpu_start_ms: pool.ticks_to_ms(0, origin), passes });
            }
        }
        Ok(())
    }

    /// Count every pass's pipeline statistics (vertex, fragment, compute invocations,
    /// primitives, clipping) from the next frame on, into [`PassTime::counts`]. False: the
    /// device cannot (no `pipelineStatisticsQuery`).
    pub fn count_pipeline_stats(&mut self) -> Result<bool, RenderError> {
        if !self.pipeline_stats.is_empty() {
            return Ok(true);
        }
        self.finish()?;
        let capacity = self.timestamps[0].capacity() / 2;
        let mut pools = Vec::new();
        for i in 0..FRAMES_IN_FLIGHT {
            match PipelineStatsPool::new(&self.ctx, &format!("pipeline_stats_{i}"), capacity)? {
                Some(p) => pools.push(p),
                None => return Ok(false),
            }
        }
        self.pipeline_stats = pools;
        Ok(true)
    }

    /// Device memory created by each technique of this renderer, and by the resources they
    /// share ("frame"), as the renderer was created.
    pub fn technique_memory(&self) -> &[TechniqueMemory] {
        &self.memory
    }

    /// Look from `camera` from the next frame on (position, target, up, field of view; its
    /// width and height must be the renderer's: a new size needs a new renderer).
    /// A camera that differs from the last one restarts what the techniques average over the
    /// frames of one view ([`Technique::camera_moved`]).
    pub fn set_camera(&mut self, camera: &Camera) {
        let exposure = self.uniforms.camera_position[3];
        let before = self.uniforms;
        set_camera_uniforms(&mut self.uniforms, camera, exposure, &self.scene);
        if bytemuck::bytes_of(&before) != bytemuck::bytes_of(&self.uniforms) {
            for t in self.techniques.iter_mut().flatten() {
                t.camera_moved();
            }
        }
    }

    /// The frames averaged into the image shown, where a technique accumulates them
    /// (`render.raytrace.accumulate`), as of the last frame rendered.
    pub fn accumulated_frames(&self) -> Option<u32> {
        self.techniques.iter().flatten().find_map(|t| t.accumulated())
    }

    /// The frame graph, to register external images (the demo's swapchain images).
    pub fn graph_mut(&mut self) -> &mut FrameGraph {
        &mut self.graph
    }

    /// Wait until the next frame's slot is free (its previous submission complete, its
    /// timings collected) and return the slot. [`Renderer::render_frame_with`] records into
    /// it; a window acquires its swapchain image in between, with the slot's semaphore.
    pub fn wait_for_next_slot(&mut self) -> Result<usize, RenderError> {
        let slot = (self.frame_index % FRAMES_IN_FLIGHT as u64) as usize;
        // Wait for this slot's previous frame; its timestamps are then readable without WAIT.
        self.commands.wait(slot)?;
        self.collect_slot(slot)?;
        Ok(slot)
    }

    /// Record and submit one frame. Timings of frames whose fences have signalled are
    /// collected into [`Renderer::take_timings`].
    /// Spread work that spans frames (the eikonal light simulation) over the frames, `budget`
    /// of it before each, so that a window stays responsive while it runs and shows it
    /// progress; None (the default) does all of it before the first frame that needs it.
    pub fn set_work_budget(&mut self, budget: Option<std::time::Duration>) {
        self.work_budget = budget;
    }

    /// Whether work that spans frames is still in progress.
    pub fn preparing(&self) -> bool {
        self.techniques.iter().flatten().any(|t| t.preparing())
    }

    /// Continue the techniques' work that spans frames before a frame is recorded: its
    /// kernels write what the frames in flight read, so they finish first.
    fn prepare_techniques(&mut self) -> Result<(), RenderError> {
        if !self.preparing() {
            return Ok(());
        }
        self.finish()?;
        let deadline = self.work_budget.map(|b| std::time::Instant::now() + b);
        for t in self.techniques.iter_mut().flatten() {
            t.prepare(&self.ctx, &mut self.graph, deadline)?;
        }
        Ok(())
    }

    pub fn render_frame(&mut self) -> Result<(), RenderError> {
        self.render_frame_with(&SubmitSync::default(), |_, _| {})
    }

    /// Record one frame, let `extra` append passes after the scene's (they see the final
    /// tone-mapped image), and submit it with the semaphores of `sync`. The demo window uses
    /// this to copy the image to the swapchain, draw its overlay and present; headless
    /// rendering is `render_frame`, which appends nothing.
    pub fn render_frame_with<'s>(
        &'s mut self,
        sync: &SubmitSync,
        extra: impl FnOnce(&mut Frame<'_, 's>, FinalImage<'s>),
    ) -> Result<(), RenderError> {
        self.prepare_techniques()?;
        let slot = self.wait_for_next_slot()?;
        self.uniforms.info[1] = self.frame_index as u32;
        self.frame_buffers[slot].write(0, bytemuck::bytes_of(&self.uniforms));

        for t in self.techniques.iter_mut().flatten() {
            if self.every_frame {
                t.contents_changed();
            }
            t.begin_frame();
        }
        let dt = if self.frame_index == 0 { None } else { self.tonemap_dt };
        self.bounds.clear();
        self.bounds.extend(self.objects.iter().map(|o| (o.bounds.0, o.tight_radius)));
        self.boxes.clear();
        self.boxes.extend(self.objects.iter().map(|o| (o.bounds.0, o.half_extent)));
        let view_proj = glam::Mat4::from_cols_array_2d(&self.uniforms.view_proj);
        let eye = Vec3::from_slice(&self.uniforms.camera_position[..3]);
        // The view's -z axis in world space: the third column of the inverse view, negated.
        let forward = -Vec3::from_slice(&self.uniforms.inv_view[2][..3]).normalize_or_zero();
        let animate = self.animation.as_ref().zip(self.animation_time.take());
        let Renderer {
            techniques,
            photon_caustics,
            frame_sets,
            scene,
            targets,
            timestamps,
            commands,
            graph,
            recipe,
            bounds,
            boxes,
            ..
        } = self;
        let shadowed = recipe.passes.iter().any(|p| p.name == crate::technique::baseline::shadow_map::SHADOW_MAP);
        let inputs = FrameInputs {
            scene,
            targets,
            photon_caustics,
            frame_set: frame_sets.sets()[slot],
            slot,
            shadow_atlas: shadowed.then_some(targets.shadow_atlas_id),
            dt,
            object_bounds: bounds,
            object_boxes: boxes,
            view_proj,
            eye,
            forward,
        };
        let cmd = commands.begin(slot)?;
        let mut frame = graph.frame();
        if let Some((animation, time)) = animate {
            animation.record(&mut frame, &scene.vertices, time);
        }
        // The frame recipe: the steps in the order they were planned. Each step must record
        // exactly the passes its technique planned for that stage, or `prism passes`, the
        // timings and the frame would disagree: checked in every build.
        for step in &recipe.steps {
            let t = techniques[step.technique].as_deref().expect("a planned technique is created");
            let first = frame.pass_count();
            t.record(step.stage, &mut frame, &inputs);
            let planned = recipe.passes[step.passes.clone()].iter().map(|p| p.name);
            let recorded = frame.pass_names_since(first);
            assert!(
                planned.clone().eq(recorded.clone()),
                "technique `{}` recorded {:?} in stage {:?}, but planned {:?}",
                TECHNIQUES[step.technique].key,
                recorded.collect::<Vec<_>>(),
                step.stage,
                planned.collect::<Vec<_>>()
            );
            // What lets a resize keep the light-space techniques.
            assert!(
                step.stage.is_image_space() || !frame.uses_any_since(first, &targets.image_sized()),
                "technique `{}` used an image-sized target in the light-space stage {:?}",
                TECHNIQUES[step.technique].key,
                step.stage
            );
        }
        extra(&mut frame, FinalImage { ldr: &targets.ldr, ldr_id: targets.ldr_id });
        // `cmd` borrows `commands` until its last use here.
        let queries = frame.execute_with(&cmd, Some(&timestamps[slot]), self.pipeline_stats.get(slot));
        commands.submit_with(slot, sync)?;
        self.pending[slot] = Some((self.frame_index, queries));
        self.frame_index += 1;
        Ok(())
    }

    /// Wait for every submitted frame and collect its timings.
    pub fn finish(&mut self) -> Result<(), RenderError> {
        for slot in 0..FRAMES_IN_FLIGHT {
            self.commands.wait(slot)?;
            self.collect_slot(slot)?;
        }
        self.completed.sort_by_key(|f| f.frame);
        Ok(())
    }

    /// Timings of every completed frame so far (and forget them).
    pub fn take_timings(&mut self) -> Vec<FrameTiming> {
        std::mem::take(&mut self.completed)
    }

    fn read_image(&mut self, id: ImageId, bytes_per_texel: u64) -> Result<Vec<u8>, RenderError> {
        self.finish()?;
        let image = if id == self.targets.hdr_id {
            &self.targets.hdr
        } else if id == self.targets.ldr_id {
            &self.targets.ldr
        } else {
            debug_targets(&self.techniques).find(|d| d.id == id).map(|d| &d.image).unwrap_or(&self.targets.ldr)
        };
        Ok(self.graph.read_back(&self.ctx, image, id, bytes_per_texel, Access::TransferRead)?)
    }

    /// Linear radiance, RGBA f32, row 0 at the top.
    pub fn read_hdr(&mut self) -> Result<Vec<f32>, RenderError> {
        let bytes = self.read_image(self.targets.hdr_id, 16)?;
        Ok(bytemuck::pod_collect_to_vec(&bytes))
    }

    /// Tone-mapped sRGB, RGBA u8, row 0 at the top.
    pub fn read_ldr(&mut self) -> Result<Vec<u8>, RenderError> {
        self.read_image(self.targets.ldr_id, 4)
    }

    /// Total flux in the caustic map (W per channel), summed over every texel of every layer
    /// (the map holds flux per texel, src/technique/caustics/caustics_map.rs); `None` without a
    /// caustics_map pass.
    pub fn caustic_map_flux(&mut self) -> Result<Option<[f64; 3]>, RenderError> {
        if self.technique::<CausticsMapPass>().is_none() {
            return Ok(None);
        }
        self.finish()?;
        let (atlas, id) = (&self.targets.caustic.flux, self.targets.caustic.flux_id);
        let bytes = self.graph.read_back(&self.ctx, atlas, id, 16, Access::FragmentSampled)?;
        let values: &[[f32; 4]] = bytemuck::cast_slice(&bytes);
        let mut sum = [0f64; 3];
        for v in values {
            for c in 0..3 {
                sum[c] += v[c] as f64;
            }
        }
        Ok(Some(sum))
    }

    /// The caustic map of `render.caustics = "caustics_map"`: flux per texel (W, RGBA f32),
    /// every layer of the atlas (six cube faces per point light, the first of its six for a
    /// directional one), and the texels per side; `None` without a caustics_map pass.
    #[allow(clippy::type_complexity)] // reason: the texels and their edge are read together
    pub fn read_caustic_map(&mut self) -> Result<Option<(Vec<[f32; 4]>, u32)>, RenderError> {
        if self.technique::<CausticsMapPass>().is_none() {
            return Ok(None);
        }
        self.finish()?;
        let (atlas, id) = (&self.targets.caustic.flux, self.targets.caustic.flux_id);
        let bytes = self.graph.read_back(&self.ctx, atlas, id, 16, Access::FragmentSampled)?;
        Ok(Some((bytemuck::pod_collect_to_vec(&bytes), atlas.desc.width)))
    }

    /// Per light map of `render.caustics = "impostor_lightmap"`, the texels its photons can
    /// reach and the apply pass draws: (lowest column, lowest row, highest column, highest row);
    /// `None` without that technique.
    pub fn read_lightmap_reach(&mut self) -> Result<Option<Vec<[u32; 4]>>, RenderError> {
        self.finish()?;
        let Some(p) = technique::<ImpostorLightmap>(&self.techniques) else { return Ok(None) };
        Ok(Some(p.read_reach(&self.ctx, &mut self.graph)?))
    }

    /// The light maps of `render.caustics = "impostor_lightmap"` (irradiance in W/m^2, RGBA f32,
    /// one layer per receiver in the order of the charts) and each receiver's (object index,
    /// area in m^2); `None` without that technique.
    #[allow(clippy::type_complexity)]
    pub fn read_lightmaps(&mut self) -> Result<Option<(Vec<[f32; 4]>, Vec<(usize, f32)>)>, RenderError> {
        self.finish()?;
        let Some(p) = technique::<ImpostorLightmap>(&self.techniques) else { return Ok(None) };
        let texels = p.read_lightmaps(&self.ctx, &mut self.graph)?;
        Ok(Some((texels, p.charts.iter().map(|c| (c.object, c.area())).collect())))
    }

    /// Shah et al. 2007 Eq. 6's V per source face, as the occlusion queries counted it, and
    /// the texels of the front refractor layer that see a specular surface (what V should
    /// count); `None` without caustics_map and `flux = "occlusion_query"`.
    pub fn caustics_map_visible(&mut self) -> Result<Option<VisibleCounts>, RenderError> {
        let on = self.technique::<CausticsMapPass>().is_some_and(|p| p.params().flux == Flux::OcclusionQuery);
        if !on {
            return Ok(None);
        }
        self.finish()?;
        let Some(p) = technique::<CausticsMapPass>(&self.techniques) else {
            return Ok(None);
        };
        let r = p.refractors();
        let (image, id, visible_id) = (&r.layers[0].0, r.layers[0].1, r.visible_id);
        let graph = &mut self.graph;
        self.ctx.one_shot(|cmd| graph.access_now(cmd, &[], &[(visible_id, Access::HostRead)]))?;
        let bytes = self.graph.read_back(&self.ctx, image, id, 16, Access::TransferRead)?;
        let faces = image.layers() as usize;
        let per_face = (image.desc.width * image.desc.height) as usize;
        let front: &[[f32; 4]] = bytemuck::cast_slice(&bytes);
        let covered =
            (0..faces).map(|f| front[f * per_face..(f + 1) * per_face].iter().filter(|t| t[3] > 0.0).count() as u32);
        let visible: &[u32] = bytemuck::cast_slice(r.visible.read());
        Ok(Some(VisibleCounts { visible: visible[..faces].to_vec(), covered: covered.collect() }))
    }

    /// The photon-buffer caustics' intermediate images (Hu & Qin 2007 §3,
    /// src/technique/caustics/photon_buffer.rs), RGBA f32 with all layers one after another; `None`
    /// without a photon_buffer pass.
    pub fn photon_buffer_images(&mut self) -> Result<Option<PhotonBufferImages>, RenderError> {
        if self.technique::<PhotonBufferPass>().is_none() {
            return Ok(None);
        }
        self.finish()?;
        let Some(p) = technique::<PhotonBufferPass>(&self.techniques) else {
            return Ok(None);
        };
        let c = &self.photon_caustics;
        let images = [(&p.photons.0, p.photons.1), (&p.flux.0, p.flux.1), (&c.textures, c.id)];
        let mut out = Vec::new();
        for (image, id) in images {
            let bytes = self.graph.read_back(&self.ctx, image, id, 16, Access::FragmentSampled)?;
            out.push((image.desc.width, bytemuck::pod_collect_to_vec::<u8, [f32; 4]>(&bytes)));
        }
        let mut it = out.into_iter();
        let mut next = || it.next().unwrap();
        let (photon_size, photons) = next();
        let (_, flux) = next();
        let (texture_size, caustics) = next();
        Ok(Some(PhotonBufferImages {
            photon_size,
            texture_size,
            photons,
            flux,
            caustics,
            rectangles: c.rectangles().to_vec(),
        }))
    }

    /// Names of the debug targets [`Renderer::read_target`] can read (e.g.
    /// `refraction_hu_qin_p2`, `refraction_hu_qin_t2` with `render.hu_qin.debug = true`).
    pub fn debug_targets(&self) -> Vec<String> {
        self.debug_target_list().map(|d| d.name.clone()).collect()
    }

    /// A debug target, RGBA f32, row 0 at the top; `None` if no pass writes one of that name.
    /// The generic read-back of [`Renderer::read_frame_image`]: debug targets are images of
    /// the frame graph like any other, RGBA32F.
    pub fn read_target(&mut self, name: &str) -> Result<Option<Vec<f32>>, RenderError> {
        let Some(id) = self.debug_target_list().find(|d| d.name == name).map(|d| d.id) else {
            return Ok(None);
        };
        let Some(image) = self.frame_images().into_iter().find(|i| i.id == id) else {
            return Ok(None);
        };
        self.read_frame_image(&image)
    }

    /// Every image the frame graph owns (../shared/DESIGN.md: the graph registers each
    /// one): G-buffer, back-face layers, impostor textures, caustic maps, volumes, ... in
    /// the order they were created, each with a unique name (a repeated name gets `~2`,
    /// `~3`, ...) and, if it cannot be read back, why.
    pub fn frame_images(&self) -> Vec<FrameImage> {
        let mut seen: Vec<String> = Vec::new();
        self.graph
            .images()
            .into_iter()
            .map(|t| {
                let repeats = seen.iter().filter(|n| **n == t.name).count();
                seen.push(t.name.clone());
                let name = if repeats == 0 { t.name.clone() } else { format!("{}~{}", t.name, repeats + 1) };
                let layout = crate::gpu::texel_layout(t.format);
                let unreadable = if layout.is_none() {
                    Some("format not decoded")
                } else if !t.written {
                    Some("never written (contents undefined)")
                } else {
                    None
                };
                FrameImage {
                    name,
                    format: format!("{:?}", t.format),
                    width: t.width,
                    height: t.height,
                    depth: t.depth,
                    layers: t.layers,
                    channels: layout.map_or(0, |(c, _)| c),
                    unreadable,
                    id: t.id,
                }
            })
            .collect()
    }

    /// One of [`Renderer::frame_images`] as f32 channels (`image.channels` per texel, in the
    /// order R, G, B, A; the depth of a depth image), layer after layer (slice after slice for
    /// a 3D image), rows from the top. Waits for the frames in flight. `None` if the image
    /// is unreadable (see [`FrameImage::unreadable`]) or no longer exists.
    pub fn read_frame_image(&mut self, image: &FrameImage) -> Result<Option<Vec<f32>>, RenderError> {
        if image.unreadable.is_some() {
            return Ok(None);
        }
        self.finish()?;
        let Some(bytes) = self.graph.read_back_image(&self.ctx, image.id)? else { return Ok(None) };
        let format = self.graph.images().into_iter().find(|t| t.id == image.id).map(|t| t.format);
        Ok(format.and_then(|f| crate::gpu::texels_to_f32(f, &bytes)))
    }
}

/// An image of the frame graph ([`Renderer::frame_images`]).
#[derive(Clone, Debug)]
pub struct FrameImage {
    /// The image's debug name, unique among the frame's images.
    pub name: String,
    /// The Vulkan format, e.g. `R32G32B32A32_SFLOAT`.
    pub format: String,
    pub width: u32,
    pub height: u32,
    /// Slices of a 3D image (a volume); 1 otherwise.
    pub depth: u32,
    pub layers: u32,
    /// f32 channels per texel that [`Renderer::read_frame_image`] returns.
    pub channels: u32,
    /// Why it cannot be read back, if it cannot.
    pub unreadable: Option<&'static str>,
    id: ImageId,
}

/// What [`Renderer::caustics_map_visible`] reads back, per source face.
pub struct VisibleCounts {
    /// Eq. 6's V as the occlusion query counted it.
    pub visible: Vec<u32>,
    /// Texels of the front refractor layer that see a specular surface.
    pub covered: Vec<u32>,
}

/// What [`Renderer::photon_buffer_images`] reads back.
pub struct PhotonBufferImages {
    /// Pixels per side of the photon buffer, and texels per side of the caustic textures.
    pub photon_size: u32,
    pub texture_size: u32,
    /// The photon buffer (u, v, k, 0) and the photons' power (rgb), one layer per source face.
    pub photons: Vec<[f32; 4]>,
    pub flux: Vec<[f32; 4]>,
    /// The filtered caustic textures, one layer per rectangle.
    pub caustics: Vec<[f32; 4]>,
    pub rectangles: Vec<crate::technique::caustics::photon_buffer::GpuPhotonRect>,
}

/// The stages that see the frame set.
const FRAME_STAGES: vk::ShaderStageFlags = vk::ShaderStageFlags::from_raw(
    vk::ShaderStageFlags::ALL_GRAPHICS.as_raw() | vk::ShaderStageFlags::COMPUTE.as_raw(),
);

/// `atlas` in a frame set: its cube-array view at `bindings[0]`, its 2D-array view at
/// `bindings[1]`.
fn bind_atlas<'a>(set: Bindings<'a>, bindings: [u32; 2], atlas: &'a Image, sampler: &'a Sampler) -> Bindings<'a> {
    set.sampled(bindings[0], atlas, sampler).sampled_view(bindings[1], atlas, atlas.array_view(), sampler)
}

/// The caustic atlas and its receivers' distances in a frame set.
fn bind_caustic_atlas<'a>(set: Bindings<'a>, c: &'a CausticAtlas, sampler: &'a Sampler) -> Bindings<'a> {
    let set = bind_atlas(set, [BINDING_CAUSTIC_CUBE, BINDING_CAUSTIC_2D], &c.flux, sampler);
    bind_atlas(set, [BINDING_CAUSTIC_RECEIVERS_CUBE, BINDING_CAUSTIC_RECEIVERS_2D], &c.receivers, sampler)
}

/// "No caustic light" and "no receiver in front" in a caustic atlas, ready to be sampled.
fn clear_caustic_atlas(ctx: &GpuContext, graph: &mut FrameGraph, c: &CausticAtlas) -> Result<(), RenderError> {
    clear_atlas(ctx, graph, &c.flux, c.flux_id, 0.0)?;
    clear_atlas(ctx, graph, &c.receivers, c.receivers_id, FAR_DISTANCE)
}

/// Hu & Qin 2007 §3's caustic textures and rectangles in a frame set.
fn bind_photon_caustics<'a>(set: Bindings<'a>, c: &'a PhotonCaustics, sampler: &'a Sampler) -> Bindings<'a> {
    set.sampled(BINDING_PHOTON_CAUSTICS, &c.textures, sampler).uniform(BINDING_PHOTON_RECTS, &c.rects)
}

/// Fill every layer of `atlas` with `value`, ready to be sampled.
fn clear_atlas(
    ctx: &GpuContext,
    graph: &mut FrameGraph,
    atlas: &Image,
    id: ImageId,
    value: f32,
) -> Result<(), RenderError> {
    ctx.one_shot(|cmd| {
        graph.access_now(cmd, &[(id, Access::TransferWrite)], &[]);
        cmd.clear_color_image(atlas, [value; 4]);
        graph.access_now(cmd, &[(id, Access::FragmentSampled)], &[]);
    })?;
    Ok(())
}

fn technique<T: Technique>(techniques: &[Option<Box<dyn Technique>>]) -> Option<&T> {
    techniques.iter().flatten().find_map(|t| (t.as_ref() as &dyn std::any::Any).downcast_ref::<T>())
}

fn debug_targets(techniques: &[Option<Box<dyn Technique>>]) -> impl Iterator<Item = &DebugTarget> {
    techniques.iter().flatten().flat_map(|t| t.debug_targets())
}

/// The camera's near-plane distance from `eye`: scaled to the scene, so that the tiny and the
/// huge behave alike.
pub fn near_plane(gpu_scene: &GpuScene, eye: Vec3) -> f32 {
    let extent = gpu_scene.bounds_radius.max(eye.distance(gpu_scene.bounds_center));
    (extent * 1e-5).max(1e-12)
}

/// View, projection and position uniforms for `cam`, with the near plane scaled to the
/// scene so that the tiny and the huge behave alike.
fn set_camera_uniforms(u: &mut FrameUniforms, cam: &Camera, exposure: f32, gpu_scene: &GpuScene) {
    let view = cam.view();
    let near = near_plane(gpu_scene, cam.position);
    let proj = camera_projection(cam.vfov_deg, cam.width as f32 / cam.height as f32, near);
    let view_proj = proj * view;
    u.view = view.to_cols_array_2d();
    u.proj = proj.to_cols_array_2d();
    u.view_proj = view_proj.to_cols_array_2d();
    u.inv_view_proj = view_proj.inverse().to_cols_array_2d();
    u.inv_view = view.inverse().to_cols_array_2d();
    u.camera_position = Vec3::extend(cam.position, exposure).to_array();
    u.clip = [near, 0.0, 0.0, 0.0];
    u.viewport = [cam.width as f32, cam.height as f32, 1.0 / cam.width as f32, 1.0 / cam.height as f32];
}

impl Renderer {
    /// Move object `name` so that its centre is at `center` (the demo window drags objects;
    /// tests move them). Waits for the frames in flight, rewrites the object's vertices, and
    /// tells the distance impostors, which are rendered again if the object left its map's
    /// reference point by more than `render.impostor.regenerate_distance` (Szirmay-Kalos et
    /// al. 2005, §6). Returns false if there is no such object.
    pub fn move_object(&mut self, name: &str, center: Vec3) -> Result<bool, RenderError> {
        let Some(index) = self.objects.iter().position(|o| o.name == name) else {
            return Ok(false);
        };
        self.finish()?;
        let o = &mut self.objects[index];
        let offset = center - o.bounds.0;
        let stride = std::mem::size_of::<Vertex>();
        let range = o.first_vertex * stride..(o.first_vertex + o.vertex_count) * stride;
        let mut vertices: Vec<Vertex> = bytemuck::pod_collect_to_vec(&self.scene.vertices.read()[range.clone()]);
        for v in &mut vertices {
            v.position = (Vec3::from(v.position) + offset).to_array();
        }
        self.scene.vertices.write(range.start, bytemuck::cast_slice(&vertices));
        o.bounds.0 = center;
        // The vertices no longer hold any scene's placement: the next update rewrites them.
        self.placement = None;
        let bounds: Vec<_> = self.objects.iter().map(|o| o.bounds).collect();
        for t in self.techniques.iter_mut().flatten() {
            t.objects_moved(&bounds);
        }
        Ok(true)
    }

    /// A distance impostor or refractor map of this renderer, if its technique is selected
    /// (the first one with `render.impostor.maps = "per_object"`).
    pub fn impostor_map(&self, effect: ImpostorEffect) -> Option<&ImpostorMap> {
        self.impostor_maps(effect).into_iter().next()
    }

    /// Every map of an effect: one shared, or one per object in scene order.
    pub fn impostor_maps(&self, effect: ImpostorEffect) -> Vec<&ImpostorMap> {
        let reflection = self.technique::<ImpostorReflection>();
        let refraction = self.technique::<ImpostorRefraction>();
        match effect {
            ImpostorEffect::Reflection => reflection.iter().flat_map(|p| &p.maps).collect(),
            ImpostorEffect::Refraction => refraction.iter().flat_map(|p| &p.instances).map(|i| &i.map).collect(),
            ImpostorEffect::Refractor => refraction.iter().flat_map(|p| &p.instances).map(|i| &i.refractor).collect(),
        }
    }

    /// Run the impostor probe kernel (glsl/impostor/probe.comp: the shaders' own `Hit()` and
    /// Fresnel terms) on a map rendered by an earlier frame; see [`ImpostorMap::probe`].
    /// `None` if the effect has no map.
    pub fn probe_impostor(
        &mut self,
        effect: ImpostorEffect,
        fresnel: bool,
        iterations: u32,
        records: &[[[f32; 4]; 3]],
    ) -> Result<Option<Vec<[[f32; 4]; 3]>>, RenderError> {
        self.finish()?;
        let reflection = technique::<ImpostorReflection>(&self.techniques);
        let refraction = technique::<ImpostorRefraction>(&self.techniques);
        let map = match effect {
            ImpostorEffect::Reflection => reflection.and_then(|p| p.maps.first()),
            ImpostorEffect::Refraction => refraction.and_then(|p| p.instances.first()).map(|i| &i.map),
            ImpostorEffect::Refractor => refraction.and_then(|p| p.instances.first()).map(|i| &i.refractor),
        };
        match map {
            Some(m) => Ok(Some(m.probe(&self.ctx, &mut self.graph, fresnel, iterations, records)?)),
            None => Ok(None),
        }
    }
}

impl Drop for Renderer {
    fn drop(&mut self) {
        // Pipelines, samplers and layouts are destroyed immediately by their wrappers: the
        // GPU must be idle first.
        let _ = self.ctx.wait_idle();
    }
}
