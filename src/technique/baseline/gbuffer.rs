//! G-buffer: the first visible surface of every object, as MRT (see glsl/gbuffer/gbuffer.frag
//! for what each channel encodes) plus reversed-Z depth.
//!
//! The meshes are drawn unculled (a quad is seen from either side, and a camera may stand
//! inside a closed object) except a closed mesh with outward normals
//! ([`crate::scene::Mesh::is_closed_outward`]) that lies wholly beyond the near plane this
//! frame: seen from outside, its nearest surface is a front face at every pixel, so its back
//! faces would only be rasterized and shaded to lose the depth test.
//!
//! Where Wyman 2005 shades a refractor, its visible front faces also carry d_N, the distance
//! along the inverted normal interpolated from the vertices (§3.1): the paper draws the front
//! faces once, with d_N a vertex attribute of the shading draw, and so does prism, in this
//! pass, instead of drawing them a second time in a layer of their own.
use glam::Vec3;

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
        let near = crate::renderer::near_plane(scene, inputs.eye);
        let culled: Vec<bool> = (scene.draws.iter().zip(inputs.object_bounds))
            .map(|(d, &b)| d.closed && beyond_near_plane(b, inputs.eye, inputs.forward, near))
            .collect();
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
                        cmd.bind_mesh_buffers(&scene.vertices, &scene.indices);
                        let mut bound = None;
                        // `draws[i]` is object i.
                        for (object, d) in scene.draws.iter().enumerate() {
                            let pipeline = &self.pipelines[usize::from(culled[object])];
                            if bound != Some(culled[object]) {
                                cmd.bind_graphics(pipeline, &[frame_set, self.set.set()]);
                                bound = Some(culled[object]);
                            }
                            cmd.push_graphics(pipeline, &GbufferPush { material: d.material, object: object as u32 });
                            cmd.draw_indexed(d.index_count, d.first_index, d.vertex_offset);
                        }
                    },
                );
            });
    }
}

/// Whether a bounding sphere (centre, radius) lies wholly beyond the near plane of a camera
/// at `eye` looking along unit `forward`: then the camera is outside it, and no part of it
/// is clipped away by the near plane to open a closed mesh's inside to the view.
pub fn beyond_near_plane((center, radius): (Vec3, f32), eye: Vec3, forward: Vec3, near: f32) -> bool {
    (center - eye).dot(forward) - radius > near
}

pub struct GBufferPass {
    target: RenderTarget,
    /// Unculled, and with back faces culled.
    pipelines: [GraphicsPipeline; 2],
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
        let pipeline = |cull| {
            GraphicsPipeline::new(
                ctx,
                &GraphicsPipelineDesc {
                    blend: &[Blend::Off, Blend::Off],
                    cull,
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
            )
        };
        let pipelines = [pipeline(vk::CullModeFlags::NONE)?, pipeline(vk::CullModeFlags::BACK)?];
        Ok(GBufferPass { target, pipelines, set, _d_n: d_n })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn back_faces_are_culled_only_from_outside_and_beyond_the_near_plane() {
        let (eye, forward, near) = (Vec3::new(0.0, 0.0, 4.0), Vec3::NEG_Z, 1e-4);
        let ball = |z: f32, r: f32| (Vec3::new(0.0, 0.0, z), r);
        assert!(beyond_near_plane(ball(0.0, 1.0), eye, forward, near));
        // The camera inside, on the surface, or the near plane cutting the ball.
        assert!(!beyond_near_plane(ball(0.0, 4.5), eye, forward, near));
        assert!(!beyond_near_plane(ball(0.0, 4.0), eye, forward, near));
        assert!(!beyond_near_plane(ball(0.0, 4.0 - 0.5 * near), eye, forward, near));
        // Beside the camera or behind it, though outside it.
        assert!(!beyond_near_plane((Vec3::new(3.0, 0.0, 4.0), 1.0), eye, forward, near));
        assert!(!beyond_near_plane(ball(6.0, 1.0), eye, forward, near));
    }
}
