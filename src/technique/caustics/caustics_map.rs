//! Caustics mapping: Shah, Konttinen & Pattanaik 2007, "Caustics Mapping: An Image-space
//! Technique for Real-time Caustics" (../shared/papers/shah2007-caustics-mapping.md).
//!
//! Three graph passes, each timed under its own name:
//!
//! 1. `caustics_map_receivers` (§III.B step 1): the diffuse receivers seen from each light,
//!    stored like the shadow maps as distances to the light (a cube for a point light, the
//!    light's orthographic map for a directional one), from which the splat-hits pass recovers
//!    the receivers' positions. Refractors are left out, so the receivers under them are seen.
//! 2. `caustics_map_refractors` (§III.B step 2): the specular objects from the light as MRT,
//!    positions and normals, into textures of the grid's resolution: the surface nearest the
//!    light (with Wyman 2005's d_N, §3.1), and the nearest surface facing away from it (the
//!    exit surface of double-surface refraction, §III.E / §IV with Wyman 2005). One source face fitted to the specular
//!    objects' bounding sphere (a perspective frustum for a point light outside it, an
//!    orthographic box for a directional light), or six cube faces for a point light inside.
//! 3. `caustics_map_hits` (§III.C-E): one compute invocation per vertex of the G x G grid of
//!    each source face (glsl/caustics/splat_hits.comp) fetches the refractor textures,
//!    refracts or reflects, estimates the receiver hit with the approximate (§III.C, Eq. 1-2)
//!    or true (appendix, Eq. 4-5) Newton-Raphson iteration, weighs the vertex's flux
//!    (Eq. 6-7) and picks the atlas layer the hit lands in. With an RGB ior each vertex does
//!    this once per channel (dispersion, Fig. 13). With `oracle = "receiver"` (an analysis
//!    tool, [`CausticsMapOracle`]) the pass runs glsl/caustics/splat_hits_oracle.comp, which
//!    replaces the receiver estimate by the exact tracer's closest diffuse hit of the same ray
//!    (its buffers in set 1, src/technique/refraction/oracle.rs), so that `prism ablation
//!    --technique caustics_map` measures the estimate's share of the error.
//! 4. `caustics_map` (§III.F): the records drawn as Gaussian point sprites with additive
//!    blending into the caustic-map atlas, each into its own layer: six cube faces per point
//!    light ("environment caustic map"), the orthographic map for a directional light. The
//!    paper draws its grid once per map; computing each vertex's path once and routing it,
//!    instead of running the whole grid for every cube face and keeping the sixth that lands
//!    there, gives the same map for a sixth of the light-path work. The hits pass also counts
//!    the records landing in each layer ([`SplatLayers`]), so that a layer no record reaches
//!    (now, or when it was last drawn) is neither drawn nor cleared: on caustic_sphere the
//!    clears of the five faces the caustic misses cost more than the splats themselves
//!    (docs/BENCHMARKS.md).
//!
//! Units: the map holds flux per texel (W). Deferred shading divides by the receiver area a
//! texel covers (glsl/shading/deferred.frag, `caustic_irradiance`), giving irradiance in
//! W/m^2 comparable with the reference's photon-mapped caustics.

use glam::{Mat4, Vec3};

use crate::frame::gpu_scene::{cube_face_views, Draw, GpuScene};
use crate::frame::targets::DEPTH_FORMAT;
use crate::gpu::{
    vk, Access, Blend, Buffer, Clear, ComputePipeline, DepthState, GpuResult, GraphicsPipeline, GraphicsPipelineDesc,
    Image, ImageDesc, ImageViewKind, MemoryLocation, OcclusionQueryPool, RenderTarget, Sampler, SamplerDesc, Spec,
};
use crate::graph::{Bindings, BoundSet, BufferId, Frame, ImageId};
use crate::scene::techniques::{CausticExit, CausticsMapOracle, CausticsMapParams, Flux, Newton, SplatSize};
use crate::scene::{Light, Material, Scene};
pub use crate::shader_structs::GpuCausticFace;
use crate::shader_structs::{CausticDrawPush, CausticHitsPush, GpuCausticSplat, RefractorPush, ShadowPush};
use crate::technique::baseline::shadow_map::FAR_DISTANCE;
use crate::technique::refraction::oracle::Oracle;
use crate::technique::refraction::refraction_wyman::scene_distance_along_normals_timed;
use crate::technique::{
    caustic_objects, in_stage, list, params, record_kept, registration, FrameInputs, PlannedPass, Regeneration,
    Registration, RenderError, Setup, Stage, Technique,
};
use crate::{
    CAUSTIC_BINDING_BACK_NORMAL, CAUSTIC_BINDING_BACK_POSITION, CAUSTIC_BINDING_CLEAR_DRAWS, CAUSTIC_BINDING_COUNTS,
    CAUSTIC_BINDING_DESTINATIONS, CAUSTIC_BINDING_DN, CAUSTIC_BINDING_FACES, CAUSTIC_BINDING_FRONT_NORMAL,
    CAUSTIC_BINDING_FRONT_POSITION, CAUSTIC_BINDING_MATERIALS, CAUSTIC_BINDING_RECEIVER_2D,
    CAUSTIC_BINDING_RECEIVER_CUBE, CAUSTIC_BINDING_SEEN, CAUSTIC_BINDING_SPANS, CAUSTIC_BINDING_SPLATS,
    CAUSTIC_BINDING_SPLAT_DRAWS, CAUSTIC_BINDING_VISIBLE, CAUSTIC_EXIT_MARCH, CAUSTIC_EXIT_WYMAN,
    CAUSTIC_FACE_ORTHOGRAPHIC, CAUSTIC_FACE_PERSPECTIVE, CAUSTIC_LAYER_BACK, CAUSTIC_LAYER_FRONT, FLUX_OCCLUSION_QUERY,
    FLUX_SOLID_ANGLE, LIGHT_DIRECTIONAL, LIGHT_POINT, NEWTON_APPROXIMATE, NEWTON_TRUE, SHADOW_LAYERS_PER_LIGHT,
    SPLAT_FIXED, SPLAT_FOOTPRINT,
};

pub const CAUSTICS_MAP_RECEIVERS: &str = "caustics_map_receivers";
pub const CAUSTICS_MAP_REFRACTORS: &str = "caustics_map_refractors";
pub const CAUSTICS_MAP_HITS: &str = "caustics_map_hits";
pub const CAUSTICS_MAP: &str = "caustics_map";

/// `render.caustics = "caustics_map"`, parameters `[render.caustics_map]`.
pub const TECHNIQUE: Registration =
    registration!("caustics = \"caustics_map\"", plan, CausticsMapPass, ["caustics_map"]);

fn plan(scene: &Scene) -> Vec<(Stage, PlannedPass)> {
    let Some((diffuse, specular)) = caustic_objects(scene, "caustics_map") else {
        return Vec::new();
    };
    let lights = scene.lights.len();
    in_stage(
        Stage::Caustics,
        [
            PlannedPass::new(
                CAUSTICS_MAP_RECEIVERS,
                format!("positions of the diffuse receivers {} seen from {lights} light(s)", list(&diffuse)),
            ),
            PlannedPass::new(
                CAUSTICS_MAP_REFRACTORS,
                format!("positions and normals of the specular {} seen from the light(s)", list(&specular)),
            ),
            PlannedPass::new(
                CAUSTICS_MAP_HITS,
                format!("where each grid vertex's light path through {} meets the receivers", list(&specular)),
            ),
            PlannedPass::new(
                CAUSTICS_MAP,
                "the grid vertices splatted into the caustic map (render.caustics = \"caustics_map\")".to_string(),
            ),
        ],
    )
}

impl Technique for CausticsMapPass {
    /// Wyman 2005 §3.1's d_N for the `exit = "wyman"` estimate (computed whatever the exit),
    /// and the oracle's tracer geometry when `oracle = "receiver"`.
    fn once_costs(&self) -> Vec<crate::technique::OnceCost> {
        let mut costs = vec![crate::technique::refraction::refraction_wyman::d_n_cost(self.refractors.d_n_ms)];
        costs.extend(self.oracle.as_ref().map(|(o, _)| o.cost()));
        costs
    }

    fn record<'a>(&'a self, _: Stage, frame: &mut Frame<'_, 'a>, inputs: &FrameInputs<'a>) {
        if !self.regeneration.rendering() {
            return record_kept(
                frame,
                &[CAUSTICS_MAP_RECEIVERS, CAUSTICS_MAP_REFRACTORS, CAUSTICS_MAP_HITS, CAUSTICS_MAP],
            );
        }
        let (scene, targets) = (inputs.scene, inputs.targets);
        frame
            .pass(CAUSTICS_MAP_RECEIVERS)
            .write(targets.caustic.receivers_id, Access::ColorAttachment)
            .write(self.receiver_depth_id, Access::DepthAttachment)
            .record(move |cmd| {
                for face in &self.receiver_faces {
                    cmd.in_target(
                        &self.receiver_target,
                        face.layer as usize,
                        &[Clear::Color([FAR_DISTANCE; 4]), Clear::Depth(1.0)],
                        |cmd| {
                            cmd.bind_graphics(&self.receiver_pipeline, &[]);
                            cmd.push_graphics(&self.receiver_pipeline, &face.push);
                            cmd.bind_mesh_buffers(&scene.vertices, &scene.indices);
                            for d in &self.receiver_draws {
                                cmd.draw_indexed(d.index_count, d.first_index, d.vertex_offset);
                            }
                        },
                    );
                }
            });

        self.refractors.record(frame, scene);

        let mut hits = frame.pass(CAUSTICS_MAP_HITS).uses(&self.hits_set);
        if let Some((_, tracer)) = &self.oracle {
            hits = hits.uses(tracer);
        }
        let splat_layers = &self.splat_layers;
        hits.uses(&splat_layers.set).record(move |cmd| {
            let mut sets = vec![self.hits_set.set()];
            sets.extend(self.oracle.as_ref().map(|(_, t)| t.set()));
            // The counts are this pass's own: after the previous frame's read, zeroed, counted
            // by the hits kernel, read by the layers kernel.
            cmd.buffer_barrier(&splat_layers.counts, Access::ComputeRead, Access::TransferWrite);
            cmd.fill_buffer(&splat_layers.counts, 0);
            cmd.buffer_barrier(&splat_layers.counts, Access::TransferWrite, Access::ComputeWrite);
            cmd.compute(&self.hits_pipeline, &sets, &self.hits_push, self.hits_groups);
            cmd.buffer_barrier(&splat_layers.counts, Access::ComputeWrite, Access::ComputeRead);
            cmd.bind_compute(&splat_layers.pipeline, &[splat_layers.set.set()]);
            cmd.dispatch(splat_layers.groups, 1, 1);
        });
        frame
            .pass(CAUSTICS_MAP)
            .uses(&self.splat_set)
            .read(splat_layers.splat_draws_id, Access::IndirectArgs)
            .read(splat_layers.clear_draws_id, Access::IndirectArgs)
            .write(targets.caustic.flux_id, Access::ColorAttachment)
            .record(move |cmd| {
                for &layer in &splat_layers.layers {
                    let offset = u64::from(layer) * 16;
                    cmd.in_target(&self.splat_target, layer as usize, &[Clear::None], |cmd| {
                        cmd.bind_graphics(&self.clear_pipeline, &[]);
                        cmd.draw_indirect(&splat_layers.clear_draws, offset);
                        cmd.bind_graphics(&self.splat_pipeline, &[self.splat_set.set()]);
                        let push = CausticDrawPush { dest: [layer, 0, self.params.map_size, 0] };
                        cmd.push_graphics(&self.splat_pipeline, &push);
                        cmd.draw_indirect(&splat_layers.splat_draws, offset);
                    });
                }
            });
    }

    fn kept(&mut self) -> Option<&mut Regeneration> {
        Some(&mut self.regeneration)
    }
}

/// Refractor textures: 32-bit float positions and normals, so that the estimate's error is
/// the technique's, not the storage's.
const LAYER_FORMAT: vk::Format = vk::Format::R32G32B32A32_SFLOAT;

/// A point light closer to the specular objects' bounding sphere than this fraction of its
/// radius (or inside it) sees them over too wide an angle for one frustum: six cube faces.
const FITTED_FRUSTUM_LIMIT: f32 = 0.9;

/// Which caustic-atlas layers the splat records reach, and the draws the GPU sizes from that
/// (glsl/caustics/splat_layers.comp): a layer that no record reaches, now or when it was last
/// drawn, is neither cleared nor drawn; a layer that records reach draws its light's records in
/// their order, as before, so its additions are the same from run to run.
struct SplatLayers {
    /// The layers drawn: a point light's six cube faces, a directional light's first layer.
    layers: Vec<u32>,
    /// Per atlas layer: records counted into it this frame (u32).
    counts: Buffer,
    /// Per atlas layer: the splat draw and the clear draw (VkDrawIndirectCommand each).
    splat_draws: Buffer,
    splat_draws_id: BufferId,
    clear_draws: Buffer,
    clear_draws_id: BufferId,
    /// The kernel that writes the draws, its set (counts, spans, draws, seen) and groups.
    pipeline: ComputePipeline,
    set: BoundSet,
    groups: u32,
    /// Per atlas layer: its light's records (first, count); host-written once.
    _spans: Buffer,
    /// Per atlas layer: the count its last drawn frame had (u32; 1 at first, so that the
    /// first frame clears every layer).
    _seen: Buffer,
}

impl SplatLayers {
    /// The layers `drawn`, and per atlas layer its light's records (first, count).
    fn new(s: &mut Setup<'_>, drawn: Vec<u32>, spans: &[[u32; 2]]) -> GpuResult<Self> {
        use vk::BufferUsageFlags as U;
        let ctx = s.ctx;
        let layers = spans.len() as u64;
        let gpu_buffer = |name: &str, bytes: u64, usage| Buffer::new(ctx, name, bytes, usage, MemoryLocation::GpuOnly);
        let counts = gpu_buffer("caustic_layer_counts", 4 * layers, U::STORAGE_BUFFER | U::TRANSFER_DST)?;
        let draws = |name| gpu_buffer(name, 16 * layers, U::STORAGE_BUFFER | U::INDIRECT_BUFFER);
        let (splat_draws, clear_draws) = (draws("caustic_splat_draws")?, draws("caustic_clear_draws")?);
        let spans = Buffer::storage(ctx, "caustic_layer_spans", spans)?;
        let seen = Buffer::storage(ctx, "caustic_layer_seen", &vec![1u32; layers as usize])?;
        let graph = &mut *s.graph;
        let (splat_draws_id, clear_draws_id) =
            (graph.register_buffer(&splat_draws), graph.register_buffer(&clear_draws));
        let seen_id = graph.register_buffer(&seen);
        // The counts are ordered by the hits pass's own barriers.
        let set = Bindings::new(vk::ShaderStageFlags::COMPUTE)
            .storage(CAUSTIC_BINDING_COUNTS, &counts)
            .storage(CAUSTIC_BINDING_SPANS, &spans)
            .storage(CAUSTIC_BINDING_SPLAT_DRAWS, &splat_draws)
            .access(splat_draws_id, Access::ComputeWrite)
            .storage(CAUSTIC_BINDING_CLEAR_DRAWS, &clear_draws)
            .access(clear_draws_id, Access::ComputeWrite)
            .storage(CAUSTIC_BINDING_SEEN, &seen)
            .access(seen_id, Access::ComputeWrite)
            .build(ctx, "caustics_map_layers")?;
        let pipeline =
            ComputePipeline::new(ctx, "caustics_map_layers", "caustics/splat_layers.comp", &[set.layout()], 0, &[])?;
        let groups = (layers as u32).div_ceil(crate::REF_WORKGROUP);
        Ok(SplatLayers {
            layers: drawn,
            counts,
            splat_draws,
            splat_draws_id,
            clear_draws,
            clear_draws_id,
            pipeline,
            set,
            groups,
            _spans: spans,
            _seen: seen,
        })
    }
}

/// A face of the receivers' distance atlas.
struct ReceiverFace {
    layer: u32,
    push: ShadowPush,
}

struct SourceFace {
    view_proj: Mat4,
    light: [f32; 4],
}

/// Where the light sees the specular objects from: the faces of its vertex grid.
fn source_faces(light: &Light, center: Vec3, radius: f32, grid: u32) -> Vec<GpuCausticFace> {
    let g = grid as f32;
    let v4 = |v: Vec3, w: f32| [v.x, v.y, v.z, w];
    match light {
        Light::Point { position, intensity } => {
            let to = center - *position;
            let d = to.length();
            let far = (d + radius) * 1.5;
            let face = |view_proj: Mat4, tan_half: f32| GpuCausticFace {
                view_proj: view_proj.to_cols_array_2d(),
                receiver_view_proj: Mat4::IDENTITY.to_cols_array_2d(),
                light: v4(*position, LIGHT_POINT as f32),
                intensity: v4(*intensity, 0.0),
                measure: [CAUSTIC_FACE_PERSPECTIVE as f32, tan_half, g, 2.0 * radius],
                origin: [0.0; 4],
            };
            if d * FITTED_FRUSTUM_LIMIT > radius {
                // The cone around the bounding sphere, with a margin of 2% for the
                // tessellation's outermost vertices.
                let tan_half = (radius / d).asin().tan() * 1.02;
                let dir = to / d;
                let up = if dir.y.abs() > 0.99 { Vec3::Z } else { Vec3::Y };
                let view = Mat4::look_at_rh(*position, center, up);
                let near = ((d - radius) * 0.5).max(d * 1e-4);
                let proj = Mat4::perspective_rh(2.0 * tan_half.atan(), 1.0, near, far);
                vec![face(proj * view, tan_half)]
            } else {
                let near = (far * 1e-4).max(1e-9);
                let proj = Mat4::perspective_rh(std::f32::consts::FRAC_PI_2, 1.0, near, far);
                cube_face_views(*position).iter().map(|v| face(proj * *v, 1.0)).collect()
            }
        }
        Light::Directional { direction, irradiance } => {
            let dir = direction.normalize();
            let r = radius * 1.02;
            let origin = center - dir * 2.0 * r;
            let up = if dir.y.abs() > 0.99 { Vec3::Z } else { Vec3::Y };
            let view = Mat4::look_at_rh(origin, origin + dir, up);
            let proj = Mat4::orthographic_rh(-r, r, -r, r, 0.0, 4.0 * r);
            vec![GpuCausticFace {
                view_proj: (proj * view).to_cols_array_2d(),
                receiver_view_proj: Mat4::IDENTITY.to_cols_array_2d(),
                light: v4(dir, LIGHT_DIRECTIONAL as f32),
                intensity: v4(*irradiance, 0.0),
                measure: [CAUSTIC_FACE_ORTHOGRAPHIC as f32, r, g, 2.0 * radius],
                origin: [0.0; 4],
            }]
        }
    }
}

pub(crate) fn is_specular(m: &Material) -> bool {
    matches!(m, Material::Dielectric { .. } | Material::Mirror { .. } | Material::Conductor { .. })
}

/// Centre and radius of a sphere bounding every specular object (around their bounding
/// box: for a ball, sqrt(3) times its radius).
fn specular_bounds(scene: &Scene) -> (Vec3, f32) {
    let (mut lo, mut hi) = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
    for o in scene.objects.iter().filter(|o| is_specular(&scene.materials[o.material])) {
        for p in &o.mesh.positions {
            lo = lo.min(*p);
            hi = hi.max(*p);
        }
    }
    let center = (lo + hi) * 0.5;
    (center, ((hi - lo).length() * 0.5).max(1e-6))
}

pub struct CausticsMapPass {
    /// The caustic maps are rendered when something changed.
    regeneration: Regeneration,
    params: CausticsMapParams,
    // Receivers: a framebuffer per atlas layer.
    receiver_target: RenderTarget,
    receiver_pipeline: GraphicsPipeline,
    _receiver_depth: Image,
    receiver_depth_id: ImageId,
    receiver_faces: Vec<ReceiverFace>,
    receiver_draws: Vec<Draw>,
    // Refractors.
    refractors: RefractorLayers,
    // Splat records: each grid vertex's light path, once.
    hits_set: BoundSet,
    hits_pipeline: ComputePipeline,
    hits_push: CausticHitsPush,
    hits_groups: [u32; 3],
    /// `oracle = "receiver"`: the exact tracer and its set 1 of the hits pass.
    oracle: Option<(Oracle, BoundSet)>,
    // Splats: a framebuffer per caustic-atlas layer.
    splat_target: RenderTarget,
    splat_set: BoundSet,
    splat_pipeline: GraphicsPipeline,
    /// A full-screen triangle writing zero flux: a layer's clear.
    clear_pipeline: GraphicsPipeline,
    splat_layers: SplatLayers,
    _faces: Buffer,
    _layer_matrices: Buffer,
    _splats: Buffer,
    _samplers: [Sampler; 2],
}

impl CausticsMapPass {
    pub fn new(s: &mut Setup<'_>) -> Result<Self, RenderError> {
        let params = params("caustics_map", CausticsMapParams::from_settings(&s.scene.render))?;
        let oracle = match params.oracle {
            CausticsMapOracle::None => None,
            CausticsMapOracle::Receiver => Some(Oracle::new(s)?),
        };
        use vk::ImageUsageFlags as U;
        let (ctx, scene, gpu, targets) = (s.ctx, s.scene, s.gpu, s.targets);
        let size = params.map_size;
        let grid = params.grid;
        let occlusion = params.flux == Flux::OcclusionQuery;
        let lights = gpu.lights.len() as u32;
        let layers = lights * SHADOW_LAYERS_PER_LIGHT;

        // 1. Receivers: the shadow pass's shaders, the diffuse draws only, into the atlas
        // that deferred shading also reads for the caustic lookup's depth test.
        let (receiver_atlas, receiver_atlas_id) = (&*targets.caustic.receivers, targets.caustic.receivers_id);
        let (receiver_depth, receiver_depth_id) = s.graph.image(
            ctx,
            &ImageDesc::square(
                "caustic_receivers_depth",
                DEPTH_FORMAT,
                size,
                layers,
                ImageViewKind::D2Array,
                U::DEPTH_STENCIL_ATTACHMENT,
            ),
        )?;
        let receiver_target =
            RenderTarget::layered(ctx, CAUSTICS_MAP_RECEIVERS, &[receiver_atlas], Some(&receiver_depth), true, layers)?;
        let receiver_pipeline = GraphicsPipeline::new(
            ctx,
            &GraphicsPipelineDesc::mesh(
                CAUSTICS_MAP_RECEIVERS,
                "shadow/shadow.vert",
                "shadow/shadow.frag",
                DepthState::LESS,
            ),
            &[],
            std::mem::size_of::<ShadowPush>() as u32,
            &receiver_target.pass,
        )?;
        let receiver_faces = gpu
            .shadow_faces
            .iter()
            .map(|face| ReceiverFace {
                layer: face.layer,
                push: ShadowPush {
                    view_proj: face.view_proj.to_cols_array_2d(),
                    light: face.light,
                    origin: face.origin,
                },
            })
            .collect();
        let draws_where = |pred: fn(&Material) -> bool| -> Vec<Draw> {
            gpu.draws.iter().filter(|d| pred(&scene.materials[d.material as usize])).copied().collect()
        };
        let receiver_draws = draws_where(Material::is_diffuse);

        // 2. Source faces of every light, and the refractor textures.
        let (refractors, faces, light_sources) =
            RefractorLayers::new(s, CAUSTICS_MAP_REFRACTORS, grid, specular_bounds(scene), occlusion)?;

        // 3. Each grid vertex's light path and hit, once (§III.C-E).
        let faces_buffer = Buffer::storage(ctx, "caustic_faces", &faces)?;
        let dispersive = scene.materials.iter().any(|m| match m {
            Material::Dielectric { ior, .. } => ior.x != ior.y || ior.y != ior.z,
            _ => false,
        });
        let channels: u32 = if dispersive { 3 } else { 1 };
        let per_face = grid * grid;
        let records = u64::from(faces.len() as u32) * u64::from(per_face) * u64::from(channels);
        let record_bytes = std::mem::size_of::<GpuCausticSplat>() as u64;
        let range = u64::from(ctx.limits().max_storage_buffer_range);
        let max_groups = ctx.limits().max_compute_work_group_count;
        let groups = u32::try_from(records).ok().and_then(|n| crate::reference::dispatch_size(n, max_groups));
        let hits_groups = match groups {
            Some(groups) if records * record_bytes <= range => groups,
            _ => {
                return Err(RenderError::Limit(format!(
                    "render.caustics_map.grid = {grid}: {} source face(s) x {grid}^2 vertices x {channels} channel(s) \
                     need {} MiB of splat records; the device's maxStorageBufferRange is {} MiB: lower the grid",
                    faces.len(),
                    (records * record_bytes) >> 20,
                    range >> 20
                )))
            }
        };
        let splats = Buffer::new(
            ctx,
            "caustic_splats",
            records * record_bytes,
            vk::BufferUsageFlags::STORAGE_BUFFER,
            MemoryLocation::GpuOnly,
        )?;
        let splats_id = s.graph.register_buffer(&splats);

        // Each atlas layer's world -> clip matrix: a point light's shadow-cube faces, a
        // directional light's orthographic map; zero (nothing drawn) for the others.
        let mut layer_matrices = vec![[[0.0f32; 4]; 4]; layers as usize];
        let mut drawn = Vec::new();
        let mut spans = vec![[0u32; 2]; layers as usize];
        for (i, l) in scene.lights.iter().enumerate() {
            let base = i as u32 * SHADOW_LAYERS_PER_LIGHT;
            let (first, count) = light_sources[i];
            let dest: Vec<(u32, Mat4)> = match l {
                Light::Point { .. } => gpu
                    .shadow_faces
                    .iter()
                    .filter(|f| f.layer >= base && f.layer < base + 6)
                    .map(|f| (f.layer, f.view_proj))
                    .collect(),
                Light::Directional { .. } => vec![(base, Mat4::from_cols_array_2d(&gpu.lights[i].view_proj))],
            };
            for (layer, view_proj) in dest {
                layer_matrices[layer as usize] = view_proj.to_cols_array_2d();
                drawn.push(layer);
                spans[layer as usize] = [first * per_face * channels, count * per_face * channels];
            }
        }
        let splat_layers = SplatLayers::new(s, drawn, &spans)?;
        let layer_matrices = Buffer::storage(ctx, "caustic_layer_matrices", &layer_matrices)?;

        // Linear filtering of the receivers' distances makes f(d) (Eq. 3) piecewise linear
        // instead of piecewise constant, so that the finite difference of Eq. 5 is not zero.
        let linear = Sampler::new(ctx, "caustic_linear", SamplerDesc::LINEAR_CLAMP)?;
        let nearest = Sampler::new(ctx, "caustic_nearest", SamplerDesc::NEAREST_CLAMP)?;
        let mut set = Bindings::new(vk::ShaderStageFlags::COMPUTE)
            .storage(CAUSTIC_BINDING_FACES, &faces_buffer)
            .storage(CAUSTIC_BINDING_MATERIALS, &gpu.materials)
            .sampled(CAUSTIC_BINDING_RECEIVER_CUBE, receiver_atlas, &linear)
            .read(receiver_atlas_id)
            .sampled_view(CAUSTIC_BINDING_RECEIVER_2D, receiver_atlas, receiver_atlas.array_view(), &linear);
        for (binding, (image, id)) in refractor_bindings().into_iter().zip(&refractors.layers) {
            set = set.sampled(binding, image, &nearest).read(*id);
        }
        set = set.storage(CAUSTIC_BINDING_VISIBLE, &refractors.visible);
        if occlusion {
            set = set.read(refractors.visible_id);
        }
        let hits_set = set
            .storage(CAUSTIC_BINDING_DESTINATIONS, &layer_matrices)
            .storage(CAUSTIC_BINDING_SPLATS, &splats)
            .access(splats_id, Access::ComputeWrite)
            .storage(CAUSTIC_BINDING_COUNTS, &splat_layers.counts)
            .build(ctx, CAUSTICS_MAP_HITS)?;
        let oracle = match oracle {
            Some(o) => {
                let set = o.set(ctx, gpu, vk::ShaderStageFlags::COMPUTE, &format!("{CAUSTICS_MAP_HITS}_tracer"))?;
                Some((o, set))
            }
            None => None,
        };
        let mut hits_layouts = vec![hits_set.layout()];
        hits_layouts.extend(oracle.as_ref().map(|(_, t)| t.layout()));
        let hits_pipeline = ComputePipeline::new(
            ctx,
            CAUSTICS_MAP_HITS,
            if oracle.is_some() { "caustics/splat_hits_oracle.comp" } else { "caustics/splat_hits.comp" },
            &hits_layouts,
            std::mem::size_of::<CausticHitsPush>() as u32,
            // Eq. 6's flux weight, the exit estimate of double-surface refraction, and the
            // splats' size.
            &[
                ("FLUX", Spec::U32(if occlusion { FLUX_OCCLUSION_QUERY } else { FLUX_SOLID_ANGLE })),
                (
                    "EXIT",
                    Spec::U32(match params.exit {
                        CausticExit::Wyman => CAUSTIC_EXIT_WYMAN,
                        CausticExit::March => CAUSTIC_EXIT_MARCH,
                    }),
                ),
                (
                    "SPLAT",
                    Spec::U32(match params.splat {
                        SplatSize::Fixed => SPLAT_FIXED,
                        SplatSize::Footprint => SPLAT_FOOTPRINT,
                    }),
                ),
                ("MAX_SIGMA", Spec::F32(params.max_splat_sigma.max(params.splat_sigma))),
            ],
        )?;
        let newton = match params.newton {
            Newton::Approximate => NEWTON_APPROXIMATE,
            Newton::True => NEWTON_TRUE,
        };
        let hits_push = CausticHitsPush {
            face: [faces.len() as u32, channels, per_face, 0],
            params: [params.splat_sigma, params.iterations as f32, newton as f32, size as f32],
        };

        // 4. The splats, each drawn into its layer (§III.F).
        let splat_set = Bindings::new(vk::ShaderStageFlags::VERTEX)
            .storage(CAUSTIC_BINDING_SPLATS, &splats)
            .read(splats_id)
            .build(ctx, CAUSTICS_MAP)?;
        // Each layer is cleared by its clear draw, where the layers kernel asks for it.
        let splat_target = RenderTarget::layered(
            ctx,
            CAUSTICS_MAP,
            &[&targets.caustic.flux],
            None,
            false,
            targets.caustic.flux.layers(),
        )?;
        let splat_pipeline = GraphicsPipeline::new(
            ctx,
            &GraphicsPipelineDesc {
                vertex_shader: "caustics/splat.vert",
                topology: vk::PrimitiveTopology::POINT_LIST,
                blend: &[Blend::Additive],
                ..GraphicsPipelineDesc::fullscreen(CAUSTICS_MAP, "caustics/splat.frag")
            },
            &[splat_set.layout()],
            std::mem::size_of::<CausticDrawPush>() as u32,
            &splat_target.pass,
        )?;
        let clear_pipeline = GraphicsPipeline::new(
            ctx,
            &GraphicsPipelineDesc {
                blend: &[Blend::Off],
                ..GraphicsPipelineDesc::fullscreen(&format!("{CAUSTICS_MAP}_clear"), "caustics/splat_clear.frag")
            },
            &[],
            0,
            &splat_target.pass,
        )?;

        Ok(CausticsMapPass {
            regeneration: Regeneration::default(),
            params,
            receiver_target,
            receiver_pipeline,
            receiver_depth_id,
            _receiver_depth: receiver_depth,
            receiver_faces,
            receiver_draws,
            refractors,
            hits_set,
            hits_pipeline,
            hits_push,
            hits_groups,
            oracle,
            splat_target,
            splat_set,
            splat_pipeline,
            clear_pipeline,
            splat_layers,
            _faces: faces_buffer,
            _layer_matrices: layer_matrices,
            _splats: splats,
            _samplers: [linear, nearest],
        })
    }

    pub fn params(&self) -> &CausticsMapParams {
        &self.params
    }

    /// The refractor layers seen from the light(s) and Eq. 6's V.
    pub fn refractors(&self) -> &RefractorLayers {
        &self.refractors
    }
}

/// The specular objects seen from every light as MRT (Shah et al. 2007, §III.B step 2):
/// positions and normals of the surface nearest the light and of the nearest surface facing
/// away from it, one array layer per source face (`source_faces`). Caustics mapping splats
/// its vertex grid from them; the photon buffer of Hu & Qin 2007 (§3.1,
/// src/technique/caustics/photon_buffer.rs) traces its photons from them.
pub struct RefractorLayers {
    name: &'static str,
    /// Per source face: the front layers' framebuffer, then the back layers'.
    front: RenderTarget,
    back: RenderTarget,
    /// Per layer (front, back): the pipeline for any mesh, and the one for a closed mesh
    /// with outward normals, which culls the faces the layer cannot keep: the back faces in
    /// the front layer (never the nearest surface: the same layer), the front faces in the
    /// back layer (the paper's "rasterizing the back-faces", §III.E; the same layer but at
    /// silhouettes, where a front face's interpolated normal may turn away from the light).
    /// The light's projections are not y-flipped like the camera's, so a front face is
    /// clockwise in their images. On a CPU device the triangles culled before setup halve
    /// the pass (docs/BENCHMARKS.md).
    front_pipelines: [GraphicsPipeline; 2],
    back_pipelines: [GraphicsPipeline; 2],
    /// front position, front normal, back position, back normal, front depth, back depth.
    pub layers: Vec<(Image, ImageId)>,
    sources: Vec<SourceFace>,
    /// The specular objects' draws.
    specular_draws: Vec<Draw>,
    /// Shah et al. 2007 Eq. 6's V: one occlusion query per source face around the front
    /// surface's draws (samples that pass the depth test), copied on the GPU into `visible`
    /// (one u32 per face), which the splat pass reads in the same frame.
    queries: Option<OcclusionQueryPool>,
    pub visible: Buffer,
    pub visible_id: BufferId,
    /// Wyman 2005's d_N per scene vertex (0 off the dielectrics), written to the front
    /// layer's position w.
    dn_set: BoundSet,
    _d_n: Buffer,
    /// Host milliseconds d_N took for the dielectrics' meshes when computed.
    pub d_n_ms: f64,
}

/// Where the caustic shaders (glsl/caustics/light_path.glsl) read the first four of
/// [`RefractorLayers::layers`].
pub fn refractor_bindings() -> [u32; 4] {
    [
        CAUSTIC_BINDING_FRONT_POSITION,
        CAUSTIC_BINDING_FRONT_NORMAL,
        CAUSTIC_BINDING_BACK_POSITION,
        CAUSTIC_BINDING_BACK_NORMAL,
    ]
}

impl RefractorLayers {
    /// The layers at `grid`^2 texels per face, recorded as the pass `name`, with the light's
    /// faces fitted to the sphere `bounds` (centre, radius) around the specular objects.
    /// Returns the source faces of every light and, per light, (its first face, its number
    /// of faces).
    #[allow(clippy::type_complexity)] // reason: the three results are built together
    pub fn new(
        s: &mut Setup<'_>,
        name: &'static str,
        grid: u32,
        bounds: (Vec3, f32),
        occlusion_queries: bool,
    ) -> GpuResult<(Self, Vec<GpuCausticFace>, Vec<(u32, u32)>)> {
        use vk::ImageUsageFlags as U;
        let (ctx, scene, gpu) = (s.ctx, s.scene, s.gpu);
        let graph = &mut *s.graph;
        let (center, radius) = bounds;
        let mut faces: Vec<GpuCausticFace> = Vec::new();
        let mut light_sources = Vec::new();
        for (i, l) in scene.lights.iter().enumerate() {
            let base = i as u32 * SHADOW_LAYERS_PER_LIGHT;
            let first = faces.len() as u32;
            for mut f in source_faces(l, center, radius, grid) {
                f.intensity[3] = base as f32;
                f.receiver_view_proj = gpu.lights[i].view_proj;
                f.origin = gpu.lights[i].origin;
                faces.push(f);
            }
            light_sources.push((first, faces.len() as u32 - first));
        }
        let n_faces = faces.len() as u32;
        let mut layer_images = Vec::new();
        for (image_name, format, usage) in [
            ("front_position", LAYER_FORMAT, U::COLOR_ATTACHMENT | U::SAMPLED | U::TRANSFER_SRC),
            ("front_normal", LAYER_FORMAT, U::COLOR_ATTACHMENT | U::SAMPLED),
            ("back_position", LAYER_FORMAT, U::COLOR_ATTACHMENT | U::SAMPLED),
            ("back_normal", LAYER_FORMAT, U::COLOR_ATTACHMENT | U::SAMPLED),
            ("front_depth", DEPTH_FORMAT, U::DEPTH_STENCIL_ATTACHMENT),
            ("back_depth", DEPTH_FORMAT, U::DEPTH_STENCIL_ATTACHMENT),
        ] {
            let desc = ImageDesc::square(
                &format!("{name}_{image_name}"),
                format,
                grid,
                n_faces,
                ImageViewKind::D2Array,
                usage,
            );
            layer_images.push(graph.image(ctx, &desc)?);
        }
        // Wyman 2005 §3.1's d_N, "precomputed for every vertex" (on the CPU, cached per mesh),
        // for the `exit = "wyman"` estimate; a one-float stand-in without vertices.
        let (d_n, d_n_ms) = scene_distance_along_normals_timed(scene);
        let d_n = if d_n.is_empty() { vec![0.0] } else { d_n };
        let d_n_buffer = Buffer::storage(ctx, &format!("{name}_d_n"), &d_n)?;
        let dn_set = Bindings::new(vk::ShaderStageFlags::VERTEX)
            .storage(CAUSTIC_BINDING_DN, &d_n_buffer)
            .build(ctx, &format!("{name}_d_n"))?;
        let l = |i: usize| &layer_images[i].0;
        let front = RenderTarget::layered(ctx, &format!("{name}_front"), &[l(0), l(1)], Some(l(4)), true, n_faces)?;
        let back = RenderTarget::layered(ctx, &format!("{name}_back"), &[l(2), l(3)], Some(l(5)), true, n_faces)?;
        let refractor_pipeline = |mode: u32, name: &str, cull| {
            GraphicsPipeline::new(
                ctx,
                &GraphicsPipelineDesc {
                    blend: &[Blend::Off, Blend::Off],
                    cull,
                    specialization: &[("MODE", Spec::U32(mode))],
                    ..GraphicsPipelineDesc::mesh(
                        name,
                        "caustics/refractor.vert",
                        "caustics/refractor.frag",
                        DepthState::LESS,
                    )
                },
                &[dn_set.layout()],
                std::mem::size_of::<RefractorPush>() as u32,
                &front.pass,
            )
        };
        use vk::CullModeFlags as Cull;
        let (front_name, back_name) = (format!("{name}_front"), format!("{name}_back"));
        let front_pipelines = [
            refractor_pipeline(CAUSTIC_LAYER_FRONT, &front_name, Cull::NONE)?,
            refractor_pipeline(CAUSTIC_LAYER_FRONT, &front_name, Cull::FRONT)?,
        ];
        let back_pipelines = [
            refractor_pipeline(CAUSTIC_LAYER_BACK, &back_name, Cull::NONE)?,
            refractor_pipeline(CAUSTIC_LAYER_BACK, &back_name, Cull::BACK)?,
        ];
        let sources = faces
            .iter()
            .map(|f| SourceFace { view_proj: Mat4::from_cols_array_2d(&f.view_proj), light: f.light })
            .collect();
        let specular_draws =
            gpu.draws.iter().filter(|d| is_specular(&scene.materials[d.material as usize])).copied().collect();
        let queries = if occlusion_queries {
            Some(OcclusionQueryPool::new(ctx, &format!("{name}_visible"), n_faces)?)
        } else {
            None
        };
        let visible = Buffer::new(
            ctx,
            &format!("{name}_visible"),
            4 * n_faces.max(1) as u64,
            vk::BufferUsageFlags::STORAGE_BUFFER | vk::BufferUsageFlags::TRANSFER_DST,
            // Host-visible so that tests can check V against the layer's covered texels.
            MemoryLocation::GpuToCpu,
        )?;
        let visible_id = graph.register_buffer(&visible);
        let layers = RefractorLayers {
            dn_set,
            _d_n: d_n_buffer,
            d_n_ms,
            queries,
            visible,
            visible_id,
            name,
            front,
            back,
            front_pipelines,
            back_pipelines,
            layers: layer_images,
            sources,
            specular_draws,
        };
        Ok((layers, faces, light_sources))
    }

    pub fn record<'a>(&'a self, frame: &mut Frame<'_, 'a>, scene: &'a GpuScene) {
        let mut pass = frame.pass(self.name).uses(&self.dn_set);
        for (i, (_, id)) in self.layers.iter().enumerate() {
            pass = pass.write(*id, if i < 4 { Access::ColorAttachment } else { Access::DepthAttachment });
        }
        if self.queries.is_some() {
            pass = pass.write(self.visible_id, Access::TransferWrite);
        }
        pass.record(move |cmd| {
            if let Some(q) = &self.queries {
                cmd.reset_occlusion_queries(q);
            }
            for (face, s) in self.sources.iter().enumerate() {
                let layers = [(&self.front, &self.front_pipelines), (&self.back, &self.back_pipelines)];
                for (layer, (target, pipelines)) in layers.into_iter().enumerate() {
                    cmd.in_target(
                        target,
                        face,
                        &[Clear::Color([0.0; 4]), Clear::Color([0.0; 4]), Clear::Depth(1.0)],
                        |cmd| {
                            // V of Eq. 6: "the number of rasterized pixels" of the front surface.
                            let query = self.queries.as_ref().filter(|_| layer == 0);
                            if let Some(q) = query {
                                cmd.begin_occlusion_query(q, face as u32);
                            }
                            cmd.bind_mesh_buffers(&scene.vertices, &scene.indices);
                            for d in &self.specular_draws {
                                let pipeline = &pipelines[usize::from(d.closed)];
                                cmd.bind_graphics(pipeline, &[self.dn_set.set()]);
                                let push = RefractorPush {
                                    view_proj: s.view_proj.to_cols_array_2d(),
                                    light: s.light,
                                    info: [d.material, 0, 0, 0],
                                };
                                cmd.push_graphics(pipeline, &push);
                                cmd.draw_indexed(d.index_count, d.first_index, d.vertex_offset);
                            }
                            if let Some(q) = query {
                                cmd.end_occlusion_query(q, face as u32);
                            }
                        },
                    );
                }
            }
            if let Some(q) = &self.queries {
                cmd.copy_occlusion_results(q, &self.visible);
            }
        });
    }
}
