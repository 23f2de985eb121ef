//! G-buffer: the first visible surface of every object, as MRT (see glsl/gbuffer/gbuffer.frag
//! for what each channel encodes) plus reversed-Z depth.
//!
//! Where Wyman 2005 shades a refractor, its visible front faces also carry d_N, the distance
//! along the inverted normal interpolated from the vertices (§3.1): the paper draws the front
//! faces once, with d_N a vertex attribute of the shading draw, and so does prism, in this
//! pass, instead of drawing them a second time in a layer of their own.
use crate::gpu::{
    vk, Access, Blend, Buffer, Clear, DepthState, GraphicsPipeline, GraphicsPipelineDesc, RenderTarget, Spec,
};
use crate::graph::{Bindings, BoundSet, Frame};
use crate::scene::Scene;
use crate::shader_structs::GbufferPush;
use crate::technique::refraction::refraction_wyman::{scene_distance_along_normals, REFRACTION_WYMAN};
use crate::technique::{
    list, refracting_objects, FrameInputs, Inputs, PlannedPass, Registration, RenderError, Setup, Stage, Technique,
};
use crate::BINDING_REFR_DN;

pub const GBUFFER: &str = "gbuffer";

/// Baseline: every frame rasterises its first visible surfaces (or clears the depth).
pub const TECHNIQUE: Registration = Registration {
    key: GBUFFER,
    plan,
    create,
    // d_N follows the refractors' meshes: re-created when they change, as Wyman's technique is.
    inputs: |scene| Inputs { settings: String::new(), placement: wyman_refractors(scene).is_some() },
};

/// The dielectrics whose d_N the G-buffer carries: those shaded by Wyman 2005.
fn wyman_refractors(scene: &Scene) -> Option<Vec<String>> {
    refracting_objects(scene, "wyman")
}

fn plan(scene: &Scene) -> Vec<(Stage, PlannedPass)> {
    let mut reason = if scene.objects.is_empty() {
        "clears depth: the scene has no objects, so the environment fills the frame".to_string()
    } else {
        format!("rasterises the first visible surface of {} object(s)", scene.objects.len())
    };
    if let Some(names) = wyman_refractors(scene) {
        reason += &format!(", with Wyman's d_N on dielectric {}", list(&names));
    }
    vec![(Stage::Surfaces, PlannedPass::new(GBUFFER, reason))]
}

fn create(s: &mut Setup<'_>) -> Result<Box<dyn Technique>, RenderError> {
    Ok(Box::new(GBufferPass::new(s)?))
}

impl Technique for GBufferPass {
    fn record<'a>(&'a self, _: Stage, frame: &mut Frame<'_, 'a>, inputs: &FrameInputs<'a>) {
        let (scene, targets, frame_set) = (inputs.scene, inputs.targets, inputs.frame_set);
        frame
            .pass(GBUFFER)
            .write(targets.gbuf_normal_id, Access::ColorAttachment)
            .write(targets.gbuf_albedo_id, Access::ColorAttachment)
            .write(targets.depth_id, Access::DepthAttachment)
            .uses(&self.set)
            .record(move |cmd| {
                // Reversed Z: clear to 0 (infinitely far).
                cmd.in_target(
                    &self.target,
                    0,
                    &[Clear::Color([0.0; 4]), Clear::Color([0.0; 4]), Clear::Depth(0.0)],
                    |cmd| {
                        cmd.bind_graphics(&self.pipeline, &[frame_set, self.set.set()]);
                        cmd.bind_mesh_buffers(&scene.vertices, &scene.indices);
                        // `draws[i]` is object i.
                        for (object, d) in scene.draws.iter().enumerate() {
                            cmd.push_graphics(
                                &self.pipeline,
                                &GbufferPush { material: d.material, object: object as u32 },
                            );
                            cmd.draw_indexed(d.index_count, d.first_index, d.vertex_offset);
                        }
                    },
                );
            });
    }
}

pub struct GBufferPass {
    target: RenderTarget,
    pipeline: GraphicsPipeline,
    /// d_N of every scene vertex at BINDING_REFR_DN; a one-float stand-in without Wyman.
    set: BoundSet,
    _d_n: Buffer,
}

impl GBufferPass {
    pub fn new(s: &mut Setup<'_>) -> Result<Self, RenderError> {
        let (ctx, targets) = (s.ctx, s.targets);
        let target =
            RenderTarget::new(ctx, GBUFFER, &[&targets.gbuf_normal, &targets.gbuf_albedo], Some(&targets.depth), true)?;
        let wyman = s.planned(REFRACTION_WYMAN);
        // The same per-mesh cache as Wyman's technique, which reports the computation's cost.
        let d_n = if wyman { scene_distance_along_normals(s.scene) } else { Vec::new() };
        let d_n = if d_n.is_empty() { vec![0.0f32] } else { d_n };
        let d_n = Buffer::storage(ctx, "gbuffer_d_n", &d_n)?;
        let set = Bindings::new(vk::ShaderStageFlags::VERTEX).storage(BINDING_REFR_DN, &d_n).build(ctx, GBUFFER)?;
        let pipeline = GraphicsPipeline::new(
            ctx,
            &GraphicsPipelineDesc {
                blend: &[Blend::Off, Blend::Off],
                specialization: &[("WYMAN_DN", Spec::U32(u32::from(wyman)))],
                ..GraphicsPipelineDesc::mesh(
                    GBUFFER,
                    "gbuffer/gbuffer.vert",
                    "gbuffer/gbuffer.frag",
                    DepthState::REVERSED_Z,
                )
            },
            &[s.frame_layout, set.layout()],
            // Push constants: material index, object index (glsl/gbuffer/gbuffer.frag).
            8,
            &target.pass,
        )?;
        Ok(GBufferPass { target, pipeline, set, _d_n: d_n })
    }
}
