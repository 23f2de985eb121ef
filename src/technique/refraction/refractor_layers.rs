//! What the two image-space refraction techniques share: the depth+normal layers of the
//! refractors (Wyman 2005 §3.2 and Fig. 3a,d; Hu & Qin 2007 Fig. 4, "initial pass") and the
//! full-screen shading pass that overwrites the dielectric pixels of the HDR target, with
//! optional debug targets holding each pixel's exit point P2 and direction T2.
//!
//! A layer is an RGBA32F normal target (see glsl/refraction/layers.frag for the channels)
//! and a D32 depth target, drawn from the refractors' draws only. Which surface it keeps:
//!
//! | layer | culling | depth test | cleared to |
//! |---|---|---|---|
//! | `Front` (nearest front face) | back faces | GREATER (reversed Z: nearest) | 0 |
//! | `BackNearest` | front faces | GREATER | 0 |
//! | `BackFurthest` | front faces | LESS (furthest) | 1 (the near plane) |
//!
//! Front faces are counter-clockwise in the (upright, y-flipped) image, as the meshes are
//! counter-clockwise seen from outside.
//!
//! A layer is either shared by every refractor (their faces compete in the depth test) or
//! kept per refractor ([`LayerScope`]): an array image with one layer per refractor, in the
//! slot order of [`refractor_slots`], each drawn from that refractor's mesh alone.
use std::sync::Arc;

use crate::frame::gpu_scene::{Draw, GpuScene};
use crate::frame::targets::{Targets, DEPTH_FORMAT, HDR_FORMAT};
use crate::gpu::{
    vk, Access, Blend, Buffer, Clear, DepthState, DescriptorSet, DescriptorSetLayout, GpuContext, GpuResult,
    GraphicsPipeline, GraphicsPipelineDesc, Image, ImageDesc, ImageViewKind, RenderTarget, Sampler, Spec, Specs,
};
use crate::graph::{Bindings, BoundSet, Frame, FrameGraph, ImageId};
use crate::scene::{Material, Scene};
use crate::technique::baseline::fullscreen::Cover;
use crate::technique::refraction::oracle::Oracle;
use crate::technique::{FrameInputs, Setup};

/// Normal layers are 32-bit float like the radiance: P2's error should be the
/// technique's, not the storage's.
pub const LAYER_FORMAT: vk::Format = vk::Format::R32G32B32A32_SFLOAT;

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LayerKind {
    Front,
    BackNearest,
    BackFurthest,
}

impl LayerKind {
    fn cull(self) -> vk::CullModeFlags {
        match self {
            LayerKind::Front => vk::CullModeFlags::BACK,
            LayerKind::BackNearest | LayerKind::BackFurthest => vk::CullModeFlags::FRONT,
        }
    }

    fn depth(self) -> (DepthState, f32) {
        match self {
            LayerKind::BackFurthest => (DepthState { test: true, write: true, compare: vk::CompareOp::LESS }, 1.0),
            _ => (DepthState::REVERSED_Z, 0.0),
        }
    }
}

/// Which refractors one layer holds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LayerScope {
    /// One image: every refractor's faces compete in the depth test, so where one refractor
    /// lies behind or in front of another the layer may hold the other's surface.
    Shared,
    /// One array layer per refractor, each holding that refractor's faces alone: a pixel's
    /// exit is then looked up on its own refractor's surface, wherever the others are.
    PerRefractor,
}

/// One layer's targets, registered with the frame graph.
pub struct Layer {
    pub kind: LayerKind,
    pub scope: LayerScope,
    pub normal: Image,
    pub depth: Image,
    pub normal_id: ImageId,
    pub depth_id: ImageId,
}

struct LayerPipeline {
    pipeline: GraphicsPipeline,
    target: RenderTarget,
    clear_depth: f32,
    scope: LayerScope,
}

/// The refractors' layers, drawn in one graph pass named `name`.
pub struct RefractorLayers {
    name: &'static str,
    pipelines: Vec<LayerPipeline>,
    pub layers: Vec<Layer>,
    /// The draws of dielectric objects.
    draws: Vec<Draw>,
}

fn is_refractor(scene: &Scene, d: &Draw) -> bool {
    matches!(scene.materials.get(d.material as usize), Some(Material::Dielectric { .. }))
}

/// Whether the G-buffer holds the refractors' [`LayerKind::Front`] layer: every object is a
/// dielectric (so every G-buffer draw is a refractor's) whose mesh is closed with outward
/// normals (so its nearest surface seen from outside is a front face). The G-buffer then
/// rasterizes the same triangles through the same transform, and at each pixel keeps the
/// nearest front face of the refractors, as the layer does. Where the near plane cuts a
/// refractor, the G-buffer shows the inside of its far side there while the layer has nothing:
/// the true front surface lies in front of the near plane, and neither holds it.
/// Not a heightfield: its surface is displaced on the GPU each frame.
pub fn gbuffer_holds_front_layer(scene: &Scene) -> bool {
    !scene.objects.is_empty()
        && scene.objects.iter().all(|o| {
            matches!(scene.material_of(o), Material::Dielectric { .. })
                && o.heightfield.is_none()
                && o.mesh.is_closed_outward()
        })
}

/// The draws whose material is a dielectric, in object order (a refractor's slot is its
/// index here).
pub fn refractor_draws(scene: &Scene, gpu: &GpuScene) -> Vec<Draw> {
    gpu.draws.iter().filter(|d| is_refractor(scene, d)).copied().collect()
}

/// Per object (`gpu.draws[i]` is object i), its refractor slot: its layer in a
/// [`LayerScope::PerRefractor`] layer, or `u32::MAX` for an object that is not a refractor.
pub fn refractor_slots(scene: &Scene, gpu: &GpuScene) -> Vec<u32> {
    let mut next = 0;
    gpu.draws
        .iter()
        .map(|d| {
            if is_refractor(scene, d) {
                next += 1;
                next - 1
            } else {
                u32::MAX
            }
        })
        .collect()
}

impl RefractorLayers {
    pub fn new(s: &mut Setup<'_>, name: &'static str, kinds: &[(LayerKind, LayerScope)]) -> GpuResult<Self> {
        let (ctx, scene, gpu, frame_layout, targets) = (s.ctx, s.scene, s.gpu, s.frame_layout, s.targets);
        let graph = &mut *s.graph;
        use vk::ImageUsageFlags as U;
        let mut layers = Vec::new();
        let mut pipelines = Vec::new();
        let draws = refractor_draws(scene, gpu);
        for (i, &(kind, scope)) in kinds.iter().enumerate() {
            let label = format!("{name}_{i}");
            let layer_count = match scope {
                LayerScope::Shared => 1,
                LayerScope::PerRefractor => draws.len().max(1) as u32,
            };
            let image = |what: &str, format, usage| {
                let desc = ImageDesc::d2(&format!("{label}_{what}"), format, targets.width, targets.height, usage);
                match scope {
                    LayerScope::Shared => desc,
                    LayerScope::PerRefractor => ImageDesc { layers: layer_count, view: ImageViewKind::D2Array, ..desc },
                }
            };
            let (normal, normal_id) =
                graph.image(ctx, &image("normal", LAYER_FORMAT, U::COLOR_ATTACHMENT | U::SAMPLED | U::TRANSFER_SRC))?;
            let depth_usage = U::DEPTH_STENCIL_ATTACHMENT | U::SAMPLED | U::TRANSFER_SRC;
            let (depth, depth_id) = graph.image(ctx, &image("depth", DEPTH_FORMAT, depth_usage))?;
            let (depth_state, clear_depth) = kind.depth();
            let target = match scope {
                LayerScope::Shared => RenderTarget::new(ctx, &label, &[&normal], Some(&depth), true)?,
                LayerScope::PerRefractor => {
                    RenderTarget::layered(ctx, &label, &[&normal], Some(&depth), true, layer_count)?
                }
            };
            let pipeline = GraphicsPipeline::new(
                ctx,
                &GraphicsPipelineDesc {
                    cull: kind.cull(),
                    ..GraphicsPipelineDesc::mesh(
                        &label,
                        "refraction/layers.vert",
                        "refraction/layers.frag",
                        depth_state,
                    )
                },
                &[frame_layout],
                0,
                &target.pass,
            )?;
            pipelines.push(LayerPipeline { pipeline, target, clear_depth, scope });
            layers.push(Layer { kind, scope, normal_id, depth_id, normal, depth });
        }
        Ok(RefractorLayers { name, pipelines, layers, draws })
    }

    pub fn layer(&self, kind: LayerKind) -> Option<&Layer> {
        self.layers.iter().find(|l| l.kind == kind)
    }

    pub fn record<'a>(&'a self, frame: &mut Frame<'_, 'a>, scene: &'a GpuScene, frame_set: DescriptorSet) {
        let mut pass = frame.pass(self.name);
        for l in &self.layers {
            pass = pass.write(l.normal_id, Access::ColorAttachment).write(l.depth_id, Access::DepthAttachment);
        }
        pass.record(move |cmd| {
            for p in &self.pipelines {
                let clears = [Clear::Color([0.0; 4]), Clear::Depth(p.clear_depth)];
                let draw = |cmd: &crate::gpu::Cmd, draws: &[Draw]| {
                    cmd.bind_graphics(&p.pipeline, &[frame_set]);
                    cmd.bind_mesh_buffers(&scene.vertices, &scene.indices);
                    for d in draws {
                        cmd.draw_indexed(d.index_count, d.first_index, d.vertex_offset);
                    }
                };
                match p.scope {
                    LayerScope::Shared => cmd.in_target(&p.target, 0, &clears, |cmd| draw(cmd, &self.draws)),
                    // Every array layer is cleared, the one of a scene without refractors too.
                    LayerScope::PerRefractor => {
                        for slot in 0..p.target.framebuffers().len() {
                            let own = self.draws.get(slot..=slot).unwrap_or(&[]);
                            cmd.in_target(&p.target, slot, &clears, |cmd| draw(cmd, own));
                        }
                    }
                }
            }
        });
    }
}

/// A debug target of a shading pass: RGBA32F, cleared to 0 each frame.
pub struct DebugTarget {
    pub name: String,
    pub image: Image,
    pub id: ImageId,
}

/// The full-screen shading of a refraction technique: reads the G-buffer and the layers,
/// overwrites the dielectric pixels of the HDR target (RT0), and with `debug` also writes
/// P2 (RT1: xyz world position, w = exit kind, 0 where none: 1 back-facing exit, 2
/// front-facing (Hu & Qin only), 3 (Wyman: any) or 4 (Hu & Qin: front) with P2 outside
/// the layer's coverage) and T2 (RT2: xyz unit
/// direction) into [`DebugTarget`]s named `<name>_p2` and `<name>_t2`.
pub struct ShadePass {
    name: &'static str,
    target: RenderTarget,
    set: BoundSet,
    pipeline: GraphicsPipeline,
    /// The dielectrics' meshes in place of the full-screen triangle, where they can be drawn:
    /// the pass shades only their pixels.
    cover: Option<Cover>,
    hdr: ImageId,
    pub debug: Vec<DebugTarget>,
    /// Set 2: the exact tracer's buffers, for an oracle ([`ShadeDesc::tracer`]).
    tracer: Option<BoundSet>,
}

pub struct ShadeDesc<'a> {
    pub name: &'static str,
    pub fragment_shader: &'a str,
    /// Set-1 inputs: (binding, image, graph id), sampled with the nearest sampler.
    pub inputs: &'a [(u32, &'a Image, ImageId)],
    /// Set-1 storage buffers read by the fragment shader: (binding, buffer).
    pub buffers: &'a [(u32, &'a Buffer)],
    /// Set-1 uniform buffers read by the fragment shader: (binding, buffer).
    pub uniforms: &'a [(u32, &'a Buffer)],
    /// Set 2: the exact tracer's (glsl/reference/trace.glsl with REF_SET 2) over the scene's
    /// vertices, bound only for an oracle; `None`: the pipeline has no set 2.
    pub tracer: Option<(&'a Oracle, &'a GpuScene)>,
    /// Specialisation constants besides `DEBUG` (the debug flag).
    pub specialization: Specs<'a>,
    pub debug: bool,
    /// The scene: the pass draws its dielectrics' meshes to shade only their pixels
    /// ([`Cover`]).
    pub scene: &'a Scene,
}

impl ShadePass {
    pub fn new(
        ctx: &Arc<GpuContext>,
        desc: &ShadeDesc<'_>,
        graph: &mut FrameGraph,
        frame_layout: &DescriptorSetLayout,
        targets: &Targets,
        nearest: &Sampler,
    ) -> GpuResult<Self> {
        let name = desc.name;
        let mut debug = Vec::new();
        if desc.debug {
            for what in ["p2", "t2"] {
                let target = format!("{name}_{what}");
                let usage = vk::ImageUsageFlags::COLOR_ATTACHMENT | vk::ImageUsageFlags::TRANSFER_SRC;
                let (image, id) =
                    graph.image(ctx, &ImageDesc::d2(&target, HDR_FORMAT, targets.width, targets.height, usage))?;
                debug.push(DebugTarget { name: target, id, image });
            }
        }
        // The HDR target keeps what earlier passes wrote; the debug targets are cleared.
        let mut colors = vec![(&targets.hdr, false)];
        colors.extend(debug.iter().map(|d| (&d.image, true)));
        let target = RenderTarget::with_clears(ctx, name, &colors)?;
        let mut set = Bindings::new(vk::ShaderStageFlags::FRAGMENT);
        for &(b, image, id) in desc.inputs {
            set = set.sampled(b, image, nearest).read(id);
        }
        // Host-written once at creation (the graph tracks images only): visible at submission.
        for &(b, buffer) in desc.buffers {
            set = set.storage(b, buffer);
        }
        for &(b, buffer) in desc.uniforms {
            set = set.uniform(b, buffer);
        }
        let set = set.build(ctx, name)?;
        let tracer = match desc.tracer {
            Some((oracle, gpu)) => {
                Some(oracle.set(ctx, gpu, vk::ShaderStageFlags::FRAGMENT, &format!("{name}_tracer"))?)
            }
            None => None,
        };
        let mut layouts = vec![frame_layout, set.layout()];
        layouts.extend(tracer.as_ref().map(|t| t.layout()));
        let mut specialization = vec![("DEBUG", Spec::U32(u32::from(desc.debug)))];
        specialization.extend_from_slice(desc.specialization);
        let blend = vec![Blend::Off; 1 + debug.len()];
        let pipeline = GraphicsPipeline::new(
            ctx,
            &GraphicsPipelineDesc {
                blend: &blend,
                specialization: &specialization,
                ..GraphicsPipelineDesc::fullscreen(name, desc.fragment_shader)
            },
            &layouts,
            0,
            &target.pass,
        )?;
        // The fragment shader discards every pixel whose G-buffer material is not a
        // dielectric: octagons around the dielectrics cover every pixel it writes.
        let scene = desc.scene;
        let dielectrics = (0..scene.objects.len())
            .filter(|&i| matches!(scene.material_of(&scene.objects[i]), Material::Dielectric { .. }));
        let cover = Cover::new(
            ctx,
            name,
            desc.fragment_shader,
            &specialization,
            &blend,
            &layouts,
            &target.pass,
            dielectrics.collect(),
        )?;
        Ok(ShadePass { name, target, set, pipeline, cover, hdr: targets.hdr_id, debug, tracer })
    }

    /// Add the pass to `frame`; `environment` is sampled through the frame set.
    pub fn record<'a>(&'a self, frame: &mut Frame<'_, 'a>, inputs: &FrameInputs<'a>) {
        let (environment, frame_set) = (inputs.scene.environment_id, inputs.frame_set);
        let cover = self.cover.as_ref().and_then(|c| Some((c, c.octagons(inputs)?)));
        let mut pass = frame.pass(self.name).read(environment, Access::FragmentSampled).uses(&self.set);
        if let Some(t) = &self.tracer {
            pass = pass.uses(t);
        }
        let mut sets = vec![frame_set, self.set.set()];
        sets.extend(self.tracer.as_ref().map(|t| t.set()));
        pass = pass.write(self.hdr, Access::ColorAttachment);
        for d in &self.debug {
            pass = pass.write(d.id, Access::ColorAttachment);
        }
        pass.record(move |cmd| {
            let mut clears = vec![Clear::None];
            clears.extend(self.debug.iter().map(|_| Clear::Color([0.0; 4])));
            cmd.in_target(&self.target, 0, &clears, |cmd| match cover {
                Some((cover, octagons)) => cover.draw(cmd, &sets, &octagons, self.target.extent()),
                None => {
                    cmd.bind_graphics(&self.pipeline, &sets);
                    cmd.draw(3, 1);
                }
            });
        });
    }
}

#[cfg(test)]
mod tests {
    use super::gbuffer_holds_front_layer;

    fn scene(objects: &str) -> crate::scene::Scene {
        let text = format!(
            "[camera]\nposition = [0, 0, 4]\ntarget = [0, 0, 0]\n[materials.glass]\ntype = \"dielectric\"\n\
             ior = 1.5\n[materials.white]\ntype = \"diffuse\"\nalbedo = 0.5\n{objects}"
        );
        crate::scene::load_str(&text, std::path::Path::new("layers.toml"), &[]).unwrap()
    }

    const BALL: &str = "[[objects]]\nmaterial = \"glass\"\nshape = \"sphere\"\ncenter = [0, 0, 0]\nradius = 1\n";

    /// The G-buffer holds the refractors' front layer only where it draws nothing but closed
    /// refractors: another object may hide one, an open mesh may show its inside.
    #[test]
    fn the_g_buffer_holds_the_front_layer_where_every_object_is_a_closed_refractor() {
        assert!(gbuffer_holds_front_layer(&scene(BALL)));
        assert!(gbuffer_holds_front_layer(&scene(&format!("{BALL}{}", BALL.replace("[0, 0, 0]", "[3, 0, 0]")))));
        assert!(!gbuffer_holds_front_layer(&scene("")), "no object");
        let diffuse = BALL.replace("\"glass\"", "\"white\"").replace("[0, 0, 0]", "[0, -3, 0]");
        assert!(!gbuffer_holds_front_layer(&scene(&format!("{BALL}{diffuse}"))), "a diffuse object besides");
        let open = "[[objects]]\nmaterial = \"glass\"\nshape = \"open_cylinder\"\ncenter = [0, 0, 0]\n\
                    radius = 1\nheight = 1\n";
        assert!(!gbuffer_holds_front_layer(&scene(open)), "an open cylinder");
    }
}
