//! Light-map caustics with distance impostors: Szirmay-Kalos, Aszódi, Lazányi, Premecz 2005,
//! "Approximate Ray-Tracing on the GPU with Distance Impostors", §5 and Fig. 9.
//! `render.caustics = "impostor_lightmap"`, parameters `[render.impostor_lightmap]`
//! ([`ImpostorLightmapParams`]).
//!
//! 1. `impostor_lightmap_uv_map`: the *uvmap* around the specular objects' centre, which "has
//!    the same structure" as the environment map "but stores the u, v coordinates and the
//!    texture id in its pixels": per texel the
//!    visible receiver's light-map (u, v), its light-map slot + 1 (the paper's texture id; 0
//!    where the visible surface has no light map) and the surface's distance from the
//!    reference point (for Hit(), §3, in the same cube: alpha). An [`ImpostorMap`] with
//!    [`MapContent::LightmapUv`], regenerated like the environment impostors (§6).
//! 2. `impostor_lightmap_refractor_map` (dielectrics only): the refractor map of §4.
//! 3. `impostor_lightmap_caustic_surfaces`: the specular objects seen from the light through a
//!    frustum fitted to their bounding sphere (a point light) or an orthographic box (a
//!    directional light), `caustic_map_size`^2 texels: position, material and normal of the
//!    nearest surface (glsl/impostor/lightmap_surface.frag).
//!    `impostor_lightmap_caustic_map`: the *caustic map*, a full-screen pass over those texels.
//!    Per texel where a specular object is visible (glsl/impostor/lightmap_caustic.frag,
//!    the paper's pixel shader, run once per texel): the light direction
//!    refracted through two surfaces (the second from the refractor map) or reflected,
//!    `l = Hit(x, R, uv map)`, the hit's (u, v, slot) from the uv map, and the photon's power
//!    (intensity x texel solid angle, or irradiance x texel area, times Fresnel and
//!    absorption); alpha -1 where there is no hit on a light-mapped receiver.
//! 4. `impostor_lightmap_splat`: one point sprite per caustic-map texel, positioned in the
//!    receiver's light map by vertex texture fetch (moved out of the clip volume for alpha < 0
//!    or another receiver), Gaussian weight in the fragment shader, additive blending. Each
//!    splat deposits power / (light-map texel area) spread by weights that sum to exactly 1
//!    over the texels it covers ([`splat_weights`]), so the light map holds irradiance in
//!    W/m^2, comparable with the reference. With `block_splats` (the default), the photons of
//!    a 2 x 2 block of caustic-map texels whose centres land within 2 ceil(radius) light-map
//!    texels of each other are one sprite whose fragments add the four Gaussians
//!    (glsl/impostor/lightmap_splat_block.vert, drawn first), and the others are drawn one by
//!    one: the same sums for a quarter of the sprites where the photons are coherent, which
//!    matters on a CPU device that sets up each sprite at a fixed cost (caustic_sphere: 12 336
//!    sprites -> 3 544, the splat 9.2 -> 5.8 ms at 512^2, docs/BENCHMARKS.md).
//! 5. `impostor_lightmap_apply` (right after deferred shading): every receiver pixel adds
//!    light-map irradiance x albedo / pi; each chart draws its own rectangle, so a pixel
//!    runs the pass only for the charts that can be seen there, and of the rectangle only the
//!    texels its photons can reach (found while rendering the caustic maps), outside which
//!    the light map is exactly 0.
//!
//! Light maps: one layer of a 2D array per chart (`lightmap_size`^2 each). Receivers: the
//! diffuse quads and boxes ([`lightmap_receivers`]); a quad's unique chart is the planar
//! projection onto its own edges, (u, v) in [0, 1]^2, a box has one such chart (and light map)
//! per face; (u, v) is evaluated per pixel from the world position in the uv map and in the
//! apply pass alike (which also matches the face by its normal). Other diffuse objects
//! (spheres, tori, lathes, meshes, heightfields) get no light map: photons that reach them are
//! dropped, and they show no caustic from this technique (docs/scene-format.md). Every light
//! has its own caustic map; a point light closer to the specular objects than their bounding
//! radius sees them through a 120-degree frustum only (photons outside it are lost).
use std::sync::Arc;

use glam::{Mat4, Vec3};

use crate::frame::gpu_scene::GpuScene;
use crate::frame::targets::{Targets, DEPTH_FORMAT};
use crate::gpu::{
    vk, Access, Blend, Buffer, Clear, DepthState, DescriptorSet, GpuContext, GpuResult, GraphicsPipeline,
    GraphicsPipelineDesc, Image, ImageDesc, ImageViewKind, MemoryLocation, RenderTarget, Sampler, SamplerDesc, Spec,
};
use crate::graph::{Bindings, BoundSet, BufferId, Frame, FrameGraph, ImageId};
use crate::scene::techniques::{ImpostorLightmapParams, ImpostorParams};
use crate::scene::{Light, Material, Scene};
use crate::shader_structs::{CausticPush, LightmapApplyPush, LightmapSplatPush};
use crate::technique::impostor::distance_impostor::{object_bounds, record_maps, ImpostorMap, MapContent, MapDesc};
use crate::technique::scene_specialization;
use crate::technique::{
    dielectric_names, in_stage, list, params, record_kept, registration, specular_names, FrameInputs, PlannedPass,
    Regeneration, Registration, RenderError, Setup, Stage, Technique,
};
use crate::{
    BINDING_GBUF_ALBEDO, BINDING_GBUF_DEPTH, BINDING_GBUF_NORMAL, BINDING_LIGHTMAPS, BINDING_LIGHTMAP_REACH,
    LIGHTMAP_BINDING_PHOTON_HIT, LIGHTMAP_BINDING_PHOTON_POWER, LIGHTMAP_BINDING_REACH, LIGHTMAP_BINDING_REFRACTOR,
    LIGHTMAP_BINDING_SURFACE_NORMAL, LIGHTMAP_BINDING_SURFACE_POSITION, LIGHTMAP_BINDING_UV_LINEAR,
    LIGHTMAP_BINDING_UV_NEAREST, LIGHT_DIRECTIONAL, LIGHT_POINT,
};

pub const IMPOSTOR_LIGHTMAP_UV_MAP: &str = "impostor_lightmap_uv_map";
pub const IMPOSTOR_LIGHTMAP_REFRACTOR_MAP: &str = "impostor_lightmap_refractor_map";
pub const IMPOSTOR_LIGHTMAP_CAUSTIC_SURFACES: &str = "impostor_lightmap_caustic_surfaces";
pub const IMPOSTOR_LIGHTMAP_CAUSTIC_MAP: &str = "impostor_lightmap_caustic_map";
pub const IMPOSTOR_LIGHTMAP_SPLAT: &str = "impostor_lightmap_splat";
pub const IMPOSTOR_LIGHTMAP_APPLY: &str = "impostor_lightmap_apply";

/// `render.caustics = "impostor_lightmap"`, parameters `[render.impostor_lightmap]`.
pub const TECHNIQUE: Registration =
    registration!("caustics = \"impostor_lightmap\"", plan, ImpostorLightmap, ["impostor_lightmap", "impostor"]);

/// The diffuse receivers that get light maps: quads (one planar chart) and boxes (one per
/// face).
pub fn lightmap_receivers(scene: &Scene) -> Vec<usize> {
    (0..scene.objects.len())
        .filter(|&i| {
            let o = &scene.objects[i];
            scene.materials[o.material].is_diffuse() && (o.shape == "quad" || o.shape == "box")
        })
        .collect()
}

/// Only with a light, a specular object, a quad or box receiver and the technique selected.
fn plan(scene: &Scene) -> Vec<(Stage, PlannedPass)> {
    let receivers: Vec<String> = lightmap_receivers(scene).iter().map(|&i| scene.objects[i].name.clone()).collect();
    if scene.render.caustics != "impostor_lightmap" || scene.lights.is_empty() || receivers.is_empty() {
        return Vec::new();
    }
    let (dielectric, specular) = (dielectric_names(scene), specular_names(scene));
    if specular.is_empty() {
        return Vec::new();
    }
    let (receivers, specular) = (list(&receivers), list(&specular));
    let mut passes = vec![PlannedPass::new(
        IMPOSTOR_LIGHTMAP_UV_MAP,
        format!("uv cube map (light-map uv + receiver id + distance) around {specular} of receivers {receivers}"),
    )];
    if !dielectric.is_empty() {
        passes.push(PlannedPass::new(
            IMPOSTOR_LIGHTMAP_REFRACTOR_MAP,
            format!("refractor map of {} for the photons' exit points", list(&dielectric)),
        ));
    }
    passes.extend([
        PlannedPass::new(
            IMPOSTOR_LIGHTMAP_CAUSTIC_SURFACES,
            format!("{specular} seen from {} light(s): positions and normals", scene.lights.len()),
        ),
        PlannedPass::new(
            IMPOSTOR_LIGHTMAP_CAUSTIC_MAP,
            format!("caustic map of {specular} from {} light(s): Hit() into the uv map", scene.lights.len()),
        ),
        PlannedPass::new(
            IMPOSTOR_LIGHTMAP_SPLAT,
            format!("Gaussian splats into the light maps of {receivers} (render.caustics = \"impostor_lightmap\")"),
        ),
    ]);
    let apply =
        PlannedPass::new(IMPOSTOR_LIGHTMAP_APPLY, format!("caustic irradiance of the light maps on {receivers}"));
    let mut out: Vec<_> = in_stage(Stage::Caustics, passes);
    out.push((Stage::Lighting, apply));
    out
}

impl Technique for ImpostorLightmap {
    fn record<'a>(&'a self, stage: Stage, frame: &mut Frame<'_, 'a>, inputs: &FrameInputs<'a>) {
        if stage == Stage::Lighting {
            self.record_apply(frame, inputs.targets, inputs.frame_set);
        } else {
            self.record(frame, inputs.scene, inputs.frame_set);
        }
    }

    fn begin_frame(&mut self) {
        ImpostorLightmap::begin_frame(self);
    }

    fn objects_moved(&mut self, bounds: &[(Vec3, f32)]) {
        ImpostorLightmap::objects_moved(self, bounds);
    }

    fn contents_changed(&mut self) {
        self.uv_map.contents_changed();
        if let Some(r) = &mut self.refractor {
            r.contents_changed();
        }
        self.regeneration.changed();
    }
}

/// Caustic map and light maps: 32-bit float, so sums of many small splats stay exact.
const MAP_FORMAT: vk::Format = vk::Format::R32G32B32A32_SFLOAT;
/// Half-angle tangent for a point light inside (or nearly inside) the specular objects'
/// bounding sphere: a 120-degree frustum towards their centre.
const INSIDE_TAN_HALF: f32 = 1.732_050_8;

/// The Gaussian weights of a splat centred at `center` (light-map pixels; pixel (i, j) has its
/// centre at (i + 0.5, j + 0.5)) with support `radius`: sigma = radius / 2, every pixel whose
/// centre lies within `radius`, normalized to sum 1. The CPU twin of
/// glsl/impostor/lightmap_splat.glsl (normalization) and lightmap_splat.frag (weights).
pub fn splat_weights(center: [f32; 2], radius: f32) -> Vec<([i32; 2], f32)> {
    let sigma = radius * 0.5;
    let r = radius.ceil() as i32;
    let base = [center[0].floor() as i32, center[1].floor() as i32];
    let mut out = Vec::new();
    for y in -r - 1..=r + 1 {
        for x in -r - 1..=r + 1 {
            let p = [base[0] + x, base[1] + y];
            let d = [p[0] as f32 + 0.5 - center[0], p[1] as f32 + 0.5 - center[1]];
            let d2 = d[0] * d[0] + d[1] * d[1];
            if d2 <= radius * radius {
                out.push((p, (-d2 / (2.0 * sigma * sigma)).exp()));
            }
        }
    }
    let sum: f32 = out.iter().map(|w| w.1).sum();
    for w in &mut out {
        w.1 /= sum;
    }
    out
}

/// A receiver's planar chart: (u, v) = ((p - origin).e_u / |e_u|^2, (p - origin).e_v / |e_v|^2),
/// from a quad's corners (the quad's own edges: a unique chart onto [0, 1]^2): a quad
/// object, or one face of a box (six charts, six light maps).
#[derive(Clone, Copy, Debug)]
pub struct Chart {
    pub object: usize,
    /// The face's quad within the object's mesh (0 for a quad; 0..6 for a box).
    pub face: u32,
    pub origin: Vec3,
    pub edge_u: Vec3,
    pub edge_v: Vec3,
}

impl Chart {
    /// The chart of a quad object ([`lightmap_receivers`]: shape "quad", corners 0, 1, 2, 3
    /// counter-clockwise, src/scene/shapes.rs).
    pub fn of_quad(scene: &Scene, object: usize, face: u32) -> Chart {
        let p = &scene.objects[object].mesh.positions[4 * face as usize..];
        Chart { object, face, origin: p[0], edge_u: p[1] - p[0], edge_v: p[3] - p[0] }
    }

    /// Every chart of a light-mapped receiver: a quad's one, a box's six faces (src/scene/
    /// shapes.rs `cuboid`: six quads of four vertices and six indices each).
    pub fn of_receiver(scene: &Scene, object: usize) -> Vec<Chart> {
        let faces = if scene.objects[object].shape == "box" { 6 } else { 1 };
        (0..faces).map(|f| Chart::of_quad(scene, object, f)).collect()
    }

    /// (u, v) = (a.p + a_w, b.p + b_w) for world position p: the uv map's push constants.
    pub fn affine(&self) -> ([f32; 4], [f32; 4]) {
        let row = |e: Vec3| {
            let a = e / e.length_squared().max(1e-30);
            [a.x, a.y, a.z, -a.dot(self.origin)]
        };
        (row(self.edge_u), row(self.edge_v))
    }

    pub fn area(&self) -> f32 {
        self.edge_u.cross(self.edge_v).length()
    }
}

/// One light's caustic map.
struct CausticMap {
    hit: Image,
    hit_id: ImageId,
    power: Image,
    power_id: ImageId,
    /// The surfaces seen from the light: xyz position, w material index + 1; xyz normal.
    surface_position: Image,
    surface_position_id: ImageId,
    surface_normal: Image,
    surface_normal_id: ImageId,
    _depth: Image,
    depth_id: ImageId,
    light: Light,
}

/// `render.caustics = "impostor_lightmap"` (§5).
pub struct ImpostorLightmap {
    pub params: ImpostorLightmapParams,
    /// The caustic maps and light maps are rendered when something changed.
    regeneration: Regeneration,
    pub uv_map: ImpostorMap,
    pub refractor: Option<ImpostorMap>,
    refractor_center: Vec3,
    /// The specular objects (drawn into the caustic maps) and their current bounds.
    specular: Vec<usize>,
    bounds: Vec<(Vec3, f32)>,
    pub charts: Vec<Chart>,
    maps: Vec<CausticMap>,
    /// The surfaces seen from the light: a framebuffer per light, and the pipeline for any
    /// mesh and the one for a closed mesh with outward normals
    /// ([`crate::scene::Mesh::is_closed_outward`]), whose back faces are never the surface
    /// nearest the light and are culled (front faces are clockwise in the light's image,
    /// which is not y-flipped like the camera's).
    surface_target: RenderTarget,
    surface_pipelines: [GraphicsPipeline; 2],
    /// The caustic map: a framebuffer and a set per light, and its full-screen pipeline.
    caustic_target: RenderTarget,
    caustic_sets: BoundSet,
    caustic_pipeline: GraphicsPipeline,
    /// Per light map, the texels its photons can reach (glsl/impostor/lightmap_caustic.frag,
    /// `extend_reach`): the apply pass draws only that part of the chart.
    reach: Buffer,
    reach_id: BufferId,
    /// One layer per receiver (`charts[i]` in layer i): irradiance in W/m^2.
    pub lightmaps: Image,
    lightmaps_id: ImageId,
    /// A framebuffer per chart.
    splat_target: RenderTarget,
    /// A set per light.
    splat_sets: BoundSet,
    splat_pipeline: GraphicsPipeline,
    /// One sprite per 2 x 2 block of photons that lie close on the light map (`block_splats`).
    block_pipeline: Option<GraphicsPipeline>,
    apply_target: RenderTarget,
    apply_set: BoundSet,
    apply_pipeline: GraphicsPipeline,
    _linear: Sampler,
    _nearest: Sampler,
}

fn specular_objects(scene: &Scene) -> Vec<usize> {
    (0..scene.objects.len())
        .filter(|&i| {
            matches!(
                scene.materials[scene.objects[i].material],
                Material::Dielectric { .. } | Material::Mirror { .. } | Material::Conductor { .. }
            )
        })
        .collect()
}

impl ImpostorLightmap {
    pub fn new(s: &mut Setup<'_>) -> Result<Self, RenderError> {
        let params = params("impostor_lightmap", ImpostorLightmapParams::from_settings(&s.scene.render))?;
        use vk::ImageUsageFlags as U;
        let (ctx, scene, frame_layout, targets) = (s.ctx, s.scene, s.frame_layout, s.targets);
        let specular = specular_objects(scene);
        let dielectric: Vec<usize> = specular
            .iter()
            .copied()
            .filter(|&i| matches!(scene.materials[scene.objects[i].material], Material::Dielectric { .. }))
            .collect();
        let map_params = ImpostorParams { resolution: params.uv_map_size, ..Default::default() };
        let uv = MapDesc {
            name: IMPOSTOR_LIGHTMAP_UV_MAP,
            label: IMPOSTOR_LIGHTMAP_UV_MAP,
            content: MapContent::LightmapUv,
            objects: specular.clone(),
        };
        let mut uv_map = ImpostorMap::new(s, uv, &map_params)?;
        let charts: Vec<Chart> =
            lightmap_receivers(scene).into_iter().flat_map(|i| Chart::of_receiver(scene, i)).collect();
        for (slot, c) in charts.iter().enumerate() {
            let (a, b) = c.affine();
            uv_map.charts[c.object].push((6 * c.face, 6, slot as u32 + 1, a, b));
        }
        let refractor = if dielectric.is_empty() {
            None
        } else {
            let desc = MapDesc {
                name: IMPOSTOR_LIGHTMAP_REFRACTOR_MAP,
                label: IMPOSTOR_LIGHTMAP_REFRACTOR_MAP,
                content: MapContent::Refractor,
                objects: dielectric,
            };
            Some(ImpostorMap::new(s, desc, &map_params)?)
        };
        let refractor_center = refractor.as_ref().map_or(Vec3::ZERO, |r| r.reference());
        let graph = &mut *s.graph;
        let linear = Sampler::new(ctx, "impostor_lightmap_linear", SamplerDesc::LINEAR_CLAMP)?;
        let nearest = Sampler::new(ctx, "impostor_lightmap_nearest", SamplerDesc::NEAREST_CLAMP)?;

        // The caustic maps: per light, a photon hit and a power map.
        let size = params.caustic_map_size;
        let mut maps = Vec::new();
        for (i, light) in scene.lights.iter().enumerate() {
            let mut image = |what: &str, format, usage| {
                graph.image(ctx, &ImageDesc::d2(&format!("impostor_lightmap_{what}_{i}"), format, size, size, usage))
            };
            let (hit, hit_id) = image("hit", MAP_FORMAT, U::COLOR_ATTACHMENT | U::SAMPLED)?;
            let (power, power_id) = image("power", MAP_FORMAT, U::COLOR_ATTACHMENT | U::SAMPLED)?;
            let (surface_position, surface_position_id) =
                image("surface_position", MAP_FORMAT, U::COLOR_ATTACHMENT | U::SAMPLED)?;
            let (surface_normal, surface_normal_id) =
                image("surface_normal", MAP_FORMAT, U::COLOR_ATTACHMENT | U::SAMPLED)?;
            let (depth, depth_id) = image("depth", DEPTH_FORMAT, U::DEPTH_STENCIL_ATTACHMENT)?;
            maps.push(CausticMap {
                hit,
                hit_id,
                power,
                power_id,
                surface_position,
                surface_position_id,
                surface_normal,
                surface_normal_id,
                _depth: depth,
                depth_id,
                light: *light,
            });
        }
        let surfaces: Vec<_> =
            maps.iter().map(|m| (vec![&m.surface_position, &m.surface_normal], Some(&m._depth))).collect();
        let surface_target = RenderTarget::each(ctx, IMPOSTOR_LIGHTMAP_CAUSTIC_SURFACES, &surfaces, true)?;
        let surface_pipeline = |cull| {
            GraphicsPipeline::new(
                ctx,
                &GraphicsPipelineDesc {
                    blend: &[Blend::Off, Blend::Off],
                    cull,
                    ..GraphicsPipelineDesc::mesh(
                        IMPOSTOR_LIGHTMAP_CAUSTIC_SURFACES,
                        "impostor/lightmap_caustic.vert",
                        "impostor/lightmap_surface.frag",
                        DepthState::LESS,
                    )
                },
                &[],
                std::mem::size_of::<CausticPush>() as u32,
                &surface_target.pass,
            )
        };
        let surface_pipelines =
            [surface_pipeline(vk::CullModeFlags::NONE)?, surface_pipeline(vk::CullModeFlags::FRONT)?];

        let reach = Buffer::new(
            ctx,
            "impostor_lightmap_reach",
            16 * charts.len().max(1) as u64,
            vk::BufferUsageFlags::STORAGE_BUFFER
                | vk::BufferUsageFlags::TRANSFER_DST
                | vk::BufferUsageFlags::TRANSFER_SRC,
            MemoryLocation::GpuOnly,
        )?;
        let reach_id = graph.register_buffer(&reach);
        let maps_out: Vec<_> = maps.iter().map(|m| (vec![&m.hit, &m.power], None)).collect();
        // The full-screen pass writes every texel: nothing to clear.
        let caustic_target = RenderTarget::each(ctx, IMPOSTOR_LIGHTMAP_CAUSTIC_MAP, &maps_out, false)?;
        // Without dielectrics the refractor map is never read: the uv map stands in.
        let refractor_cube = refractor.as_ref().unwrap_or(&uv_map);
        let caustic_sets = maps.iter().map(|m| {
            let set = Bindings::new(vk::ShaderStageFlags::FRAGMENT)
                .sampled(LIGHTMAP_BINDING_UV_LINEAR, &uv_map.cube, &linear)
                .read(uv_map.cube_id)
                .sampled(LIGHTMAP_BINDING_UV_NEAREST, &uv_map.cube, &nearest)
                .sampled(LIGHTMAP_BINDING_REFRACTOR, &refractor_cube.cube, &linear);
            // read() tracks the resource declared just before it.
            let set = match &refractor {
                Some(r) => set.read(r.cube_id),
                None => set,
            };
            set.sampled(LIGHTMAP_BINDING_SURFACE_POSITION, &m.surface_position, &nearest)
                .read(m.surface_position_id)
                .sampled(LIGHTMAP_BINDING_SURFACE_NORMAL, &m.surface_normal, &nearest)
                .read(m.surface_normal_id)
                .storage(LIGHTMAP_BINDING_REACH, &reach)
                .access(reach_id, Access::FragmentStorageWrite)
        });
        let caustic_sets = Bindings::build_each(ctx, IMPOSTOR_LIGHTMAP_CAUSTIC_MAP, caustic_sets.collect())?;
        let caustic_pipeline = GraphicsPipeline::new(
            ctx,
            &GraphicsPipelineDesc {
                blend: &[Blend::Off, Blend::Off],
                specialization: &[
                    ("ITERATIONS", Spec::U32(params.iterations)),
                    ("LIGHTMAP_SIZE", Spec::U32(params.lightmap_size)),
                    ("FILTER_RADIUS", Spec::F32(params.filter_radius)),
                ],
                ..GraphicsPipelineDesc::fullscreen(IMPOSTOR_LIGHTMAP_CAUSTIC_MAP, "impostor/lightmap_caustic.frag")
            },
            &[frame_layout, caustic_sets.layout()],
            std::mem::size_of::<CausticPush>() as u32,
            &caustic_target.pass,
        )?;

        // The light maps and the splat pass: a framebuffer per chart, a set per light.
        let n = params.lightmap_size;
        let (lightmaps, lightmaps_id) = graph.image(
            ctx,
            &ImageDesc::square(
                "impostor_lightmaps",
                MAP_FORMAT,
                n,
                charts.len().max(1) as u32,
                ImageViewKind::D2Array,
                U::COLOR_ATTACHMENT | U::SAMPLED | U::TRANSFER_SRC,
            ),
        )?;
        let splat_target =
            RenderTarget::layered(ctx, IMPOSTOR_LIGHTMAP_SPLAT, &[&lightmaps], None, true, charts.len() as u32)?;
        let splat_sets = maps.iter().map(|m| {
            Bindings::new(vk::ShaderStageFlags::VERTEX)
                .sampled(LIGHTMAP_BINDING_PHOTON_HIT, &m.hit, &nearest)
                .read(m.hit_id)
                .sampled(LIGHTMAP_BINDING_PHOTON_POWER, &m.power, &nearest)
                .read(m.power_id)
        });
        let splat_sets = Bindings::build_each(ctx, IMPOSTOR_LIGHTMAP_SPLAT, splat_sets.collect())?;
        let splat_pipeline = |vertex_shader, fragment_shader, specialization: &[(&str, Spec)]| {
            GraphicsPipeline::new(
                ctx,
                &GraphicsPipelineDesc {
                    vertex_shader,
                    topology: vk::PrimitiveTopology::POINT_LIST,
                    blend: &[Blend::Additive],
                    specialization,
                    ..GraphicsPipelineDesc::fullscreen(IMPOSTOR_LIGHTMAP_SPLAT, fragment_shader)
                },
                &[splat_sets.layout()],
                std::mem::size_of::<LightmapSplatPush>() as u32,
                &splat_target.pass,
            )
        };
        let blocks = [("BLOCKS", Spec::U32(u32::from(params.block_splats)))];
        let block_pipeline = if params.block_splats {
            Some(splat_pipeline("impostor/lightmap_splat_block.vert", "impostor/lightmap_splat_block.frag", &[])?)
        } else {
            None
        };
        let splat_pipeline = splat_pipeline("impostor/lightmap_splat.vert", "impostor/lightmap_splat.frag", &blocks)?;

        // The apply pass: additive onto the deferred result.
        let apply_target = RenderTarget::new(ctx, IMPOSTOR_LIGHTMAP_APPLY, &[&targets.hdr], None, false)?;
        let apply_set = Bindings::new(vk::ShaderStageFlags::FRAGMENT)
            .sampled(BINDING_GBUF_NORMAL, &targets.gbuf_normal, &nearest)
            .read(targets.gbuf_normal_id)
            .sampled(BINDING_GBUF_ALBEDO, &targets.gbuf_albedo, &nearest)
            .read(targets.gbuf_albedo_id)
            .sampled(BINDING_GBUF_DEPTH, &targets.depth, &nearest)
            .read(targets.depth_id)
            .sampled(BINDING_LIGHTMAPS, &lightmaps, &linear)
            .read(lightmaps_id)
            .stages(vk::ShaderStageFlags::VERTEX)
            .storage(BINDING_LIGHTMAP_REACH, &reach)
            .read(reach_id)
            .build(ctx, IMPOSTOR_LIGHTMAP_APPLY)?;
        let mut apply_specialization = scene_specialization(scene).to_vec();
        apply_specialization.push(("LIGHTMAP_SIZE", Spec::U32(n)));
        let apply_pipeline = GraphicsPipeline::new(
            ctx,
            &GraphicsPipelineDesc {
                blend: &[Blend::Additive],
                vertex_shader: "impostor/lightmap_apply.vert",
                specialization: &apply_specialization,
                ..GraphicsPipelineDesc::fullscreen(IMPOSTOR_LIGHTMAP_APPLY, "impostor/lightmap_apply.frag")
            },
            &[frame_layout, apply_set.layout()],
            std::mem::size_of::<LightmapApplyPush>() as u32,
            &apply_target.pass,
        )?;
        let bounds = (0..scene.objects.len()).map(|i| object_bounds(scene, i)).collect();
        Ok(ImpostorLightmap {
            regeneration: Regeneration::default(),
            params,
            uv_map,
            refractor,
            refractor_center,
            specular,
            bounds,
            charts,
            maps,
            surface_target,
            surface_pipelines,
            caustic_target,
            caustic_sets,
            caustic_pipeline,
            reach,
            reach_id,
            lightmaps,
            lightmaps_id,
            splat_target,
            splat_sets,
            splat_pipeline,
            block_pipeline,
            apply_target,
            apply_set,
            apply_pipeline,
            _linear: linear,
            _nearest: nearest,
        })
    }

    /// Objects moved (`bounds[i]`: object i's centre and radius): the uv map follows (§6), the
    /// refractor map moves with its objects, the caustic maps' frusta are refitted.
    pub fn objects_moved(&mut self, bounds: &[(Vec3, f32)]) {
        self.uv_map.objects_moved(bounds);
        if let Some(r) = &mut self.refractor {
            r.objects_moved(bounds);
            self.refractor_center = r.center_of(bounds);
        }
        self.bounds = bounds.to_vec();
        self.regeneration.changed();
    }

    pub fn begin_frame(&mut self) {
        self.regeneration.begin_frame();
        self.uv_map.begin_frame();
        if let Some(r) = &mut self.refractor {
            r.begin_frame();
        }
    }

    /// The specular objects' bounding sphere.
    fn specular_sphere(&self) -> (Vec3, f32) {
        let (mut lo, mut hi) = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
        for &i in &self.specular {
            let (c, r) = self.bounds[i];
            lo = lo.min(c - Vec3::splat(r));
            hi = hi.max(c + Vec3::splat(r));
        }
        let center = (lo + hi) * 0.5;
        let radius =
            self.specular.iter().map(|&i| self.bounds[i].0.distance(center) + self.bounds[i].1).fold(0.0, f32::max);
        (center, radius.max(1e-6))
    }

    /// The light's clip transform and its texel measure (tan of the half angle, or the half
    /// side in metres), and the push constant's light vector.
    fn light_view(&self, light: &Light) -> (Mat4, f32, [f32; 4], [f32; 3]) {
        let (center, radius) = self.specular_sphere();
        match light {
            Light::Point { position, intensity } => {
                let to = center - *position;
                let d = to.length();
                let dir = if d > 0.0 { to / d } else { Vec3::NEG_Y };
                let tan_half = if d * 0.9 > radius {
                    ((radius / d).asin().tan() * 1.02).min(INSIDE_TAN_HALF)
                } else {
                    INSIDE_TAN_HALF
                };
                let up = if dir.y.abs() > 0.99 { Vec3::Z } else { Vec3::Y };
                let view = Mat4::look_to_rh(*position, dir, up);
                let far = (d + radius) * 1.5;
                let near = ((d - radius) * 0.5).max(far * 1e-5);
                let proj = Mat4::perspective_rh(2.0 * tan_half.atan(), 1.0, near, far);
                (proj * view, tan_half, position.extend(LIGHT_POINT as f32).to_array(), intensity.to_array())
            }
            Light::Directional { direction, irradiance } => {
                let dir = direction.normalize();
                let r = radius * 1.02;
                let origin = center - dir * 2.0 * r;
                let up = if dir.y.abs() > 0.99 { Vec3::Z } else { Vec3::Y };
                let view = Mat4::look_to_rh(origin, dir, up);
                let proj = Mat4::orthographic_rh(-r, r, -r, r, 0.0, 4.0 * r);
                (proj * view, r, dir.extend(LIGHT_DIRECTIONAL as f32).to_array(), irradiance.to_array())
            }
        }
    }

    /// The maps, the caustic maps and the splats: before the G-buffer.
    pub fn record<'a>(&'a self, frame: &mut Frame<'_, 'a>, scene: &'a GpuScene, frame_set: DescriptorSet) {
        record_maps(frame, IMPOSTOR_LIGHTMAP_UV_MAP, vec![&self.uv_map], scene, frame_set, None);
        if let Some(r) = &self.refractor {
            record_maps(frame, IMPOSTOR_LIGHTMAP_REFRACTOR_MAP, vec![r], scene, frame_set, None);
        }
        if !self.regeneration.rendering() {
            return record_kept(
                frame,
                &[IMPOSTOR_LIGHTMAP_CAUSTIC_SURFACES, IMPOSTOR_LIGHTMAP_CAUSTIC_MAP, IMPOSTOR_LIGHTMAP_SPLAT],
            );
        }
        let size = self.params.caustic_map_size as f32;
        let pushes: Vec<(CausticPush, Vec<usize>)> = self
            .maps
            .iter()
            .map(|m| {
                let (view_proj, measure, light, intensity) = self.light_view(&m.light);
                let push = CausticPush {
                    view_proj: view_proj.to_cols_array_2d(),
                    light,
                    intensity: [intensity[0], intensity[1], intensity[2], 0.0],
                    reference: self.uv_map.reference().extend(measure).to_array(),
                    refractor: self.refractor_center.extend(size).to_array(),
                };
                (push, self.specular.clone())
            })
            .collect();
        let mut pass = frame.pass(IMPOSTOR_LIGHTMAP_CAUSTIC_SURFACES).write(self.reach_id, Access::TransferWrite);
        for m in &self.maps {
            pass = pass
                .write(m.surface_position_id, Access::ColorAttachment)
                .write(m.surface_normal_id, Access::ColorAttachment)
                .write(m.depth_id, Access::DepthAttachment);
        }
        let surface_pushes = pushes.clone();
        pass.record(move |cmd| {
            // Every light map's reach empty (lowest texels u32::MAX, highest 0) until the
            // caustic maps' photons extend it.
            cmd.fill_buffer(&self.reach, u32::MAX);
            for (i, (push, objects)) in surface_pushes.into_iter().enumerate() {
                let clears = [Clear::Color([0.0; 4]), Clear::Color([0.0; 4]), Clear::Depth(1.0)];
                cmd.in_target(&self.surface_target, i, &clears, |cmd| {
                    cmd.bind_mesh_buffers(&scene.vertices, &scene.indices);
                    for i in objects {
                        let Some(d) = scene.draws.get(i) else { continue };
                        let pipeline = &self.surface_pipelines[usize::from(d.closed)];
                        cmd.bind_graphics(pipeline, &[]);
                        let mut p = push;
                        p.intensity[3] = d.material as f32;
                        cmd.push_graphics(pipeline, &p);
                        cmd.draw_indexed(d.index_count, d.first_index, d.vertex_offset);
                    }
                });
            }
        });
        let mut pass = frame.pass(IMPOSTOR_LIGHTMAP_CAUSTIC_MAP).uses(&self.caustic_sets);
        for m in &self.maps {
            pass = pass.write(m.hit_id, Access::ColorAttachment).write(m.power_id, Access::ColorAttachment);
        }
        pass.record(move |cmd| {
            for (i, ((push, _), &set)) in pushes.into_iter().zip(self.caustic_sets.sets()).enumerate() {
                cmd.in_target(&self.caustic_target, i, &[Clear::None, Clear::None], |cmd| {
                    cmd.bind_graphics(&self.caustic_pipeline, &[frame_set, set]);
                    cmd.push_graphics(&self.caustic_pipeline, &push);
                    cmd.draw(3, 1);
                });
            }
        });

        let pass = frame
            .pass(IMPOSTOR_LIGHTMAP_SPLAT)
            .write(self.lightmaps_id, Access::ColorAttachment)
            .uses(&self.splat_sets);
        let n = self.params.lightmap_size;
        let photons = self.params.caustic_map_size * self.params.caustic_map_size;
        let blocks = self.params.caustic_map_size.div_ceil(2);
        pass.record(move |cmd| {
            for (slot, chart) in self.charts.iter().enumerate() {
                cmd.in_target(&self.splat_target, slot, &[Clear::Color([0.0; 4])], |cmd| {
                    let texel_area = chart.area() / (n as f32 * n as f32);
                    let push = LightmapSplatPush {
                        params: [self.params.filter_radius, n as f32, 1.0 / texel_area.max(1e-30), 0.0],
                        info: [slot as u32, self.params.caustic_map_size, 0, 0],
                    };
                    for &set in self.splat_sets.sets() {
                        // The blocks drawn as one sprite first, then every other photon.
                        if let Some(block) = &self.block_pipeline {
                            cmd.bind_graphics(block, &[set]);
                            cmd.push_graphics(block, &push);
                            cmd.draw(blocks * blocks, 1);
                        }
                        cmd.bind_graphics(&self.splat_pipeline, &[set]);
                        cmd.push_graphics(&self.splat_pipeline, &push);
                        cmd.draw(photons, 1);
                    }
                });
            }
        });
    }

    /// Light-map irradiance x albedo / pi on the receivers: right after deferred shading.
    pub fn record_apply<'a>(&'a self, frame: &mut Frame<'_, 'a>, targets: &Targets, frame_set: DescriptorSet) {
        frame
            .pass(IMPOSTOR_LIGHTMAP_APPLY)
            .uses(&self.apply_set)
            .write(targets.hdr_id, Access::ColorAttachment)
            .record(move |cmd| {
                cmd.in_target(&self.apply_target, 0, &[Clear::None], |cmd| {
                    cmd.bind_graphics(&self.apply_pipeline, &[frame_set, self.apply_set.set()]);
                    for (slot, c) in self.charts.iter().enumerate() {
                        let push = LightmapApplyPush {
                            origin: c.origin.extend(slot as f32).to_array(),
                            edge_u: c.edge_u.extend(c.object as f32).to_array(),
                            edge_v: c.edge_v.extend(0.0).to_array(),
                        };
                        cmd.push_graphics(&self.apply_pipeline, &push);
                        // The chart's rectangle: two triangles (impostor/lightmap_apply.vert).
                        cmd.draw(6, 1);
                    }
                });
            });
    }

    /// Read the light maps back (RGBA f32, layer after layer; `charts[i]` is layer i). For
    /// tests; waits for the GPU.
    pub fn read_lightmaps(&self, ctx: &Arc<GpuContext>, graph: &mut FrameGraph) -> GpuResult<Vec<[f32; 4]>> {
        let bytes = graph.read_back(ctx, &self.lightmaps, self.lightmaps_id, 16, Access::FragmentSampled)?;
        Ok(bytemuck::pod_collect_to_vec(&bytes))
    }

    /// Per light map (`charts[i]`), the texels the apply pass draws: (lowest column, lowest
    /// row, highest column, highest row), lowest above highest where no photon landed. For
    /// tests; waits for the GPU.
    pub fn read_reach(&self, ctx: &Arc<GpuContext>, graph: &mut FrameGraph) -> GpuResult<Vec<[u32; 4]>> {
        let bytes = graph.read_back_buffer(ctx, &self.reach, self.reach_id, 16 * self.charts.len() as u64)?;
        let raw: Vec<[u32; 4]> = bytemuck::pod_collect_to_vec(&bytes);
        Ok(raw.into_iter().map(|[a, b, c, d]| [a, b, u32::MAX - c, u32::MAX - d]).collect())
    }
}

#[cfg(test)]
mod tests {
    use super::splat_weights;

    /// Every splat deposits exactly its power: the weights sum to 1 wherever the centre falls
    /// and whatever the support, and they fall off with distance (CPU twin of the shaders).
    #[test]
    fn splat_weights_are_normalized() {
        for radius in [0.75f32, 1.0, 1.5, 2.0, 3.7, 8.0, 16.0] {
            for (cx, cy) in [(10.0f32, 10.0f32), (10.5, 10.5), (10.25, 10.9), (10.999, 10.001)] {
                let w = splat_weights([cx, cy], radius);
                assert!(!w.is_empty(), "radius {radius} at ({cx}, {cy}) covers no texel");
                let sum: f32 = w.iter().map(|w| w.1).sum();
                assert!((sum - 1.0).abs() < 1e-5, "radius {radius}: sum {sum}");
                assert!(w.iter().all(|w| w.1.is_finite() && w.1 > 0.0));
                // The texel holding the centre has the largest weight.
                let max = w.iter().map(|w| w.1).fold(0.0, f32::max);
                let own = w.iter().find(|w| w.0 == [cx.floor() as i32, cy.floor() as i32]).map(|w| w.1);
                assert_eq!(own, Some(max), "radius {radius} at ({cx}, {cy})");
                // glsl/impostor/lightmap_splat.glsl sums, and its point covers, the 2 ceil(r) + 1
                // texels from ceil(c - r - 1/2) on along each axis: every weighted texel is there.
                let span = 2 * radius.ceil() as i32 + 1;
                let lo = [(cx - radius - 0.5).ceil() as i32, (cy - radius - 0.5).ceil() as i32];
                for (p, _) in &w {
                    let inside = (0..2).all(|a| p[a] >= lo[a] && p[a] < lo[a] + span);
                    assert!(inside, "radius {radius} at ({cx}, {cy}): texel {p:?} outside {lo:?} + {span}");
                }
            }
        }
    }
}
