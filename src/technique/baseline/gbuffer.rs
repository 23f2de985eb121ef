//! G-buffer: the first visible surface of every object, as MRT (see glsl/gbuffer/gbuffer.frag
//! for what each channel encodes) plus reversed-Z depth.
use std::sync::Arc;

use crate::frame::targets::Targets;
use crate::gpu::{
    Access, Blend, Clear, DepthState, DescriptorSetLayout, GpuContext, GpuResult, GraphicsPipeline,
    GraphicsPipelineDesc, RenderTarget,
};
use crate::graph::Frame;
use crate::shader_structs::GbufferPush;
use crate::technique::{no_inputs, FrameInputs, PlannedPass, Registration, RenderError, Setup, Stage, Technique};

pub const GBUFFER: &str = "gbuffer";

/// Baseline: every frame rasterises its first visible surfaces (or clears the depth).
pub const TECHNIQUE: Registration = Registration { key: GBUFFER, plan, create, inputs: no_inputs };

fn plan(scene: &crate::scene::Scene) -> Vec<(Stage, PlannedPass)> {
    let reason = if scene.objects.is_empty() {
        "clears depth: the scene has no objects, so the environment fills the frame".to_string()
    } else {
        format!("rasterises the first visible surface of {} object(s)", scene.objects.len())
    };
    vec![(Stage::Surfaces, PlannedPass::new(GBUFFER, reason))]
}

fn create(s: &mut Setup<'_>) -> Result<Box<dyn Technique>, RenderError> {
    Ok(Box::new(GBufferPass::new(s.ctx, s.frame_layout, s.targets)?))
}

impl Technique for GBufferPass {
    fn record<'a>(&'a self, _: Stage, frame: &mut Frame<'_, 'a>, inputs: &FrameInputs<'a>) {
        let (scene, targets, frame_set) = (inputs.scene, inputs.targets, inputs.frame_set);
        frame
            .pass(GBUFFER)
            .write(targets.gbuf_normal_id, Access::ColorAttachment)
            .write(targets.gbuf_albedo_id, Access::ColorAttachment)
            .write(targets.depth_id, Access::DepthAttachment)
            .record(move |cmd| {
                // Reversed Z: clear to 0 (infinitely far).
                cmd.in_target(
                    &self.target,
                    0,
                    &[Clear::Color([0.0; 4]), Clear::Color([0.0; 4]), Clear::Depth(0.0)],
                    |cmd| {
                        cmd.bind_graphics(&self.pipeline, &[frame_set]);
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
}

impl GBufferPass {
    pub fn new(ctx: &Arc<GpuContext>, frame_layout: &DescriptorSetLayout, targets: &Targets) -> GpuResult<Self> {
        let target =
            RenderTarget::new(ctx, GBUFFER, &[&targets.gbuf_normal, &targets.gbuf_albedo], Some(&targets.depth), true)?;
        let pipeline = GraphicsPipeline::new(
            ctx,
            &GraphicsPipelineDesc {
                blend: &[Blend::Off, Blend::Off],
                ..GraphicsPipelineDesc::mesh(
                    GBUFFER,
                    "common/mesh.vert",
                    "gbuffer/gbuffer.frag",
                    DepthState::REVERSED_Z,
                )
            },
            &[frame_layout],
            // Push constants: material index, object index (glsl/gbuffer/gbuffer.frag).
            8,
            &target.pass,
        )?;
        Ok(GBufferPass { target, pipeline })
    }
}
