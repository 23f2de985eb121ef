//! Shadow maps: a cube of six faces for each point light, an orthographic map for each
//! directional light, all layers of one R32F atlas holding the distance to the light
//! (see glsl/shadow/shadow.frag for why distance rather than depth). Rendered when something
//! moved ([`Regeneration`]).
//!
//! Both sides of a surface cast (quads and the ring are open), except a closed mesh with
//! outward normals ([`crate::scene::Mesh::is_closed_outward`]) seen from a light outside its
//! bounding sphere and beyond the light's near plane: the nearest surface along every light
//! ray is then one of its front faces, and its back faces are culled.
use std::sync::Arc;

use crate::frame::gpu_scene::{GpuScene, ShadowFace};
use crate::frame::targets::Targets;
use glam::Vec3;

use crate::gpu::{
    vk, Access, Clear, DepthState, GpuContext, GpuResult, GraphicsPipeline, GraphicsPipelineDesc, RenderTarget,
};
use crate::graph::Frame;
use crate::shader_structs::ShadowPush;
use crate::technique::{
    describe_lights, diffuse_names, list, placement, record_kept, FrameInputs, PlannedPass, Regeneration, Registration,
    RenderError, Setup, Stage, Technique,
};
use crate::LIGHT_POINT;

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
        // Per face, per object: whether its back faces are culled.
        let culled: Vec<Vec<bool>> = self
            .faces
            .iter()
            .map(|f| scene.draws.iter().zip(inputs.object_bounds).map(|(d, &b)| d.closed && outside(f, b)).collect())
            .collect();
        frame
            .pass(SHADOW_MAP)
            .write(targets.shadow_atlas_id, Access::ColorAttachment)
            .write(targets.shadow_depth_id, Access::DepthAttachment)
            .record(move |cmd| {
                for (face, culled) in self.faces.iter().zip(&culled) {
                    cmd.in_target(
                        &self.target,
                        face.layer as usize,
                        &[Clear::Color([FAR_DISTANCE; 4]), Clear::Depth(1.0)],
                        |cmd| {
                            let push = ShadowPush {
                                view_proj: face.view_proj.to_cols_array_2d(),
                                light: face.light,
                                origin: face.origin,
                            };
                            cmd.bind_mesh_buffers(&scene.vertices, &scene.indices);
                            let mut bound = None;
                            // `draws[i]` is object i.
                            for (object, d) in scene.draws.iter().enumerate() {
                                let pipeline = &self.pipelines[usize::from(culled[object])];
                                if bound != Some(culled[object]) {
                                    cmd.bind_graphics(pipeline, &[]);
                                    cmd.push_graphics(pipeline, &push);
                                    bound = Some(culled[object]);
                                }
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

/// Whether a bounding sphere (centre, radius) lies outside the light of `face` and wholly
/// beyond its near plane, whose corners are sqrt(3) near from a point light (a cube face
/// spans 90 degrees); a directional light's box begins before every object.
pub fn outside(face: &ShadowFace, (center, radius): (Vec3, f32)) -> bool {
    face.light[3] != LIGHT_POINT as f32
        || center.distance(Vec3::from_slice(&face.light[..3])) - radius > 3f32.sqrt() * face.near
}

pub struct ShadowMapPass {
    /// One framebuffer per atlas layer.
    target: RenderTarget,
    /// Unculled, and with back faces culled. The light's projections are not y-flipped like
    /// the camera's: a front face is clockwise in their images, so the back faces are the
    /// counter-clockwise ones, culled as `FRONT`.
    pipelines: [GraphicsPipeline; 2],
    faces: Vec<ShadowFace>,
    regeneration: Regeneration,
}

impl ShadowMapPass {
    pub fn new(ctx: &Arc<GpuContext>, gpu: &GpuScene, targets: &Targets) -> GpuResult<Self> {
        let (atlas, depth) = (&targets.shadow_atlas, &targets.shadow_depth);
        let target = RenderTarget::layered(ctx, SHADOW_MAP, &[atlas], Some(depth), true, atlas.layers())?;
        let pipeline = |cull| {
            let desc = GraphicsPipelineDesc {
                cull,
                ..GraphicsPipelineDesc::mesh(SHADOW_MAP, "shadow/shadow.vert", "shadow/shadow.frag", DepthState::LESS)
            };
            GraphicsPipeline::new(ctx, &desc, &[], std::mem::size_of::<ShadowPush>() as u32, &target.pass)
        };
        let pipelines = [pipeline(vk::CullModeFlags::NONE)?, pipeline(vk::CullModeFlags::FRONT)?];
        Ok(ShadowMapPass { target, pipelines, faces: gpu.shadow_faces.clone(), regeneration: Regeneration::default() })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Mat4;

    #[test]
    fn back_faces_are_culled_only_for_objects_outside_the_light_and_its_near_plane() {
        let point = |near: f32| ShadowFace {
            layer: 0,
            view_proj: Mat4::IDENTITY,
            light: [0.0, 5.0, 0.0, LIGHT_POINT as f32],
            origin: [0.0; 4],
            near,
        };
        let ball = |y: f32, r: f32| (Vec3::new(0.0, y, 0.0), r);
        assert!(outside(&point(1e-3), ball(1.2, 1.0)));
        // The light inside the ball, on it, or the near plane's corners reaching into it.
        assert!(!outside(&point(1e-3), ball(4.5, 1.0)));
        assert!(!outside(&point(1e-3), ball(4.0, 1.0)));
        assert!(!outside(&point(0.1), ball(3.85, 1.0)));
        // A directional light's box begins before every object.
        let sun = ShadowFace { light: [0.0, -1.0, 0.0, crate::LIGHT_DIRECTIONAL as f32], near: 0.0, ..point(0.0) };
        assert!(outside(&sun, ball(4.5, 1.0)));
    }
}
