//! Shadow maps: a cube of six faces for each point light, an orthographic map for each
//! directional light, all layers of one R32F atlas holding the distance to the light
//! (see glsl/shadow/shadow.frag for why distance rather than depth). Rendered when something
//! moved ([`Regeneration`]).
use std::sync::Arc;

use crate::frame::gpu_scene::{GpuScene, ShadowFace};
use crate::frame::targets::Targets;
use crate::gpu::{
    Access, Clear, DepthState, GpuContext, GpuResult, GraphicsPipeline, GraphicsPipelineDesc, RenderTarget,
};
use crate::graph::Frame;
use crate::shader_structs::ShadowPush;
use crate::technique::{
    describe_lights, diffuse_names, list, placement, record_kept, FrameInputs, PlannedPass, Regeneration, Registration,
    RenderError, Setup, Stage, Technique,
};

pub const SHADOW_MAP: &str = "shadow_map";

/// Baseline: every light's shadow map, when a light has a diffuse receiver to shadow.
pub const TECHNIQUE: Registration = Registration { key: SHADOW_MAP, plan, create, inputs: placement };

fn plan(scene: &crate::scene::Scene) -> Vec<(Stage, PlannedPass)> {
    let diffuse = diffuse_names(scene);
    if scene.lights.is_empty() || diffuse.is_empty() {
        return Vec::new();
    }
    let reason =
        format!("{} cast shadows on the diffuse receivers {}", describe_lights(scene, " and "), list(&diffuse));
    vec![(Stage::Shadows, PlannedPass::new(SHADOW_MAP, reason))]
}

fn create(s: &mut Setup<'_>) -> Result<Box<dyn Technique>, RenderError> {
    Ok(Box::new(ShadowMapPass::new(s.ctx, s.gpu, s.targets)?))
}

impl Technique for ShadowMapPass {
    fn record<'a>(&'a self, _: Stage, frame: &mut Frame<'_, 'a>, inputs: &FrameInputs<'a>) {
        if !self.regeneration.rendering() {
            return record_kept(frame, &[SHADOW_MAP]);
        }
        let (scene, targets) = (inputs.scene, inputs.targets);
        frame
            .pass(SHADOW_MAP)
            .write(targets.shadow_atlas_id, Access::ColorAttachment)
            .write(targets.shadow_depth_id, Access::DepthAttachment)
            .record(move |cmd| {
                for face in &self.faces {
                    cmd.in_target(
                        &self.target,
                        face.layer as usize,
                        &[Clear::Color([FAR_DISTANCE; 4]), Clear::Depth(1.0)],
                        |cmd| {
                            cmd.bind_graphics(&self.pipeline, &[]);
                            cmd.push_graphics(
                                &self.pipeline,
                                &ShadowPush {
                                    view_proj: face.view_proj.to_cols_array_2d(),
                                    light: face.light,
                                    origin: face.origin,
                                },
                            );
                            cmd.bind_mesh_buffers(&scene.vertices, &scene.indices);
                            for d in &scene.draws {
                                cmd.draw_indexed(d.index_count, d.first_index, d.vertex_offset);
                            }
                        },
                    );
                }
            });
    }

    fn kept(&mut self) -> Option<&mut Regeneration> {
        Some(&mut self.regeneration)
    }
}

/// Cleared distance: "no occluder in this direction".
pub const FAR_DISTANCE: f32 = 3.0e38;

pub struct ShadowMapPass {
    /// One framebuffer per atlas layer.
    target: RenderTarget,
    pipeline: GraphicsPipeline,
    faces: Vec<ShadowFace>,
    regeneration: Regeneration,
}

impl ShadowMapPass {
    pub fn new(ctx: &Arc<GpuContext>, scene: &GpuScene, targets: &Targets) -> GpuResult<Self> {
        let (atlas, depth) = (&targets.shadow_atlas, &targets.shadow_depth);
        let target = RenderTarget::layered(ctx, SHADOW_MAP, &[atlas], Some(depth), true, atlas.layers())?;
        // Both sides cast: open shapes (quads, the ring) have no back to rely on.
        let desc = GraphicsPipelineDesc::mesh(SHADOW_MAP, "shadow/shadow.vert", "shadow/shadow.frag", DepthState::LESS);
        let pipeline = GraphicsPipeline::new(ctx, &desc, &[], std::mem::size_of::<ShadowPush>() as u32, &target.pass)?;
        Ok(ShadowMapPass { target, pipeline, faces: scene.shadow_faces.clone(), regeneration: Regeneration::default() })
    }
}
