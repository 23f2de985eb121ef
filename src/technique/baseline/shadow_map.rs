//! Shadow maps: a cube of six faces for each point light, an orthographic map for each
//! directional light, all layers of one R32F atlas holding the distance to the light
//! (see glsl/shadow/shadow.frag for why distance rather than depth). Rendered when something
//! moved ([`Regeneration`]). Each face draws only the objects whose bounding spheres reach
//! into its frustum: a point light's cube sees most objects in one or two of its six faces.
use std::sync::Arc;

use glam::{Mat4, Vec3, Vec4};

use crate::frame::gpu_scene::{GpuScene, ShadowFace};
use crate::frame::targets::Targets;
use crate::gpu::{
    Access, Clear, DepthState, GpuContext, GpuResult, GraphicsPipeline, GraphicsPipelineDesc, RenderTarget,
};
use crate::graph::Frame;
use crate::shader_structs::ShadowPush;
use crate::technique::impostor::distance_impostor::object_bounds;
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
    let mut pass = ShadowMapPass::new(s.ctx, s.gpu, s.targets)?;
    let scene = s.scene;
    pass.bounds = (0..scene.objects.len()).map(|i| object_bounds(scene, i)).collect();
    // The window moves a heightfield's vertices on the GPU without telling the techniques.
    pass.animated = scene.objects.iter().map(|o| o.heightfield.is_some()).collect();
    Ok(Box::new(pass))
}

/// Whether the sphere (`center`, `radius`) reaches into the side planes of the frustum of
/// `view_proj` (x and y within w in clip space: Gribb and Hartmann's planes, rows 3 +- 0 and
/// 3 +- 1). Conservative: false only where the whole sphere is outside one plane, so a face
/// that leaves out such an object renders what it rendered with it. Near and far bound the
/// whole scene (src/frame/gpu_scene.rs) and are not tested.
pub fn sphere_in_frustum(view_proj: Mat4, center: Vec3, radius: f32) -> bool {
    let m = view_proj.transpose();
    let (r0, r1, r3) = (m.x_axis, m.y_axis, m.w_axis);
    [r3 + r0, r3 - r0, r3 + r1, r3 - r1].iter().all(|plane: &Vec4| {
        let n = plane.truncate().length();
        !(n > 0.0) || plane.truncate().dot(center) + plane.w >= -radius * n
    })
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
                            for (i, d) in scene.draws.iter().enumerate() {
                                if self.reaches(face, i) {
                                    cmd.draw_indexed(d.index_count, d.first_index, d.vertex_offset);
                                }
                            }
                        },
                    );
                }
            });
    }

    fn kept(&mut self) -> Option<&mut Regeneration> {
        Some(&mut self.regeneration)
    }

    fn objects_moved(&mut self, bounds: &[(Vec3, f32)]) {
        self.bounds = bounds.to_vec();
        self.regeneration.changed();
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
    /// Per object (`scene.draws[i]` is object i): its bounding sphere, and whether the window
    /// animates its vertices (drawn into every face).
    bounds: Vec<(Vec3, f32)>,
    animated: Vec<bool>,
}

impl ShadowMapPass {
    pub fn new(ctx: &Arc<GpuContext>, scene: &GpuScene, targets: &Targets) -> GpuResult<Self> {
        let (atlas, depth) = (&targets.shadow_atlas, &targets.shadow_depth);
        let target = RenderTarget::layered(ctx, SHADOW_MAP, &[atlas], Some(depth), true, atlas.layers())?;
        // Both sides cast: open shapes (quads, the ring) have no back to rely on.
        let desc = GraphicsPipelineDesc::mesh(SHADOW_MAP, "shadow/shadow.vert", "shadow/shadow.frag", DepthState::LESS);
        let pipeline = GraphicsPipeline::new(ctx, &desc, &[], std::mem::size_of::<ShadowPush>() as u32, &target.pass)?;
        Ok(ShadowMapPass {
            target,
            pipeline,
            faces: scene.shadow_faces.clone(),
            regeneration: Regeneration::default(),
            bounds: Vec::new(),
            animated: Vec::new(),
        })
    }

    /// Whether object `i` can cast into `face` (true where its bounds are unknown).
    fn reaches(&self, face: &ShadowFace, i: usize) -> bool {
        match (self.bounds.get(i), self.animated.get(i)) {
            (Some(&(center, radius)), Some(false)) => sphere_in_frustum(face.view_proj, center, radius),
            _ => true,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::sphere_in_frustum;
    use crate::frame::gpu_scene::cube_face_views;
    use glam::{Mat4, Vec3};

    /// Never culls a sphere that has a point inside a cube face's frustum: spheres all around
    /// a point light, each sampled on its surface and at its centre; and culls those clearly
    /// off to one side (a ball below the light is in the -y face only).
    #[test]
    fn a_sphere_with_a_point_in_the_frustum_is_never_culled() {
        let light = Vec3::new(0.3, 5.0, -0.2);
        let proj = Mat4::perspective_rh(std::f32::consts::FRAC_PI_2, 1.0, 1e-3, 100.0);
        let faces: Vec<Mat4> = cube_face_views(light).iter().map(|v| proj * *v).collect();
        let inside = |m: Mat4, p: Vec3| {
            let c = m * p.extend(1.0);
            c.w > 0.0 && c.x.abs() <= c.w && c.y.abs() <= c.w
        };
        let mut seed = 12345u32;
        let mut next = || {
            seed = seed.wrapping_mul(1664525).wrapping_add(1013904223);
            (seed >> 8) as f32 / (1u32 << 24) as f32
        };
        let (mut culled, mut total) = (0, 0);
        for _ in 0..2000 {
            let c = light + Vec3::new(next() - 0.5, next() - 0.5, next() - 0.5) * 12.0;
            let r = next() * 2.0 + 0.01;
            for &m in &faces {
                total += 1;
                if sphere_in_frustum(m, c, r) {
                    continue;
                }
                culled += 1;
                assert!(!inside(m, c), "centre {c} inside, sphere culled");
                for k in 0..200 {
                    let (u, v) = (next() * 2.0 - 1.0, next() * std::f32::consts::TAU);
                    let d = Vec3::new((1.0 - u * u).sqrt() * v.cos(), u, (1.0 - u * u).sqrt() * v.sin());
                    assert!(!inside(m, c + d * r), "sphere {c} r {r}: surface point {k} inside, culled");
                }
            }
        }
        assert!(culled * 3 > total, "only {culled} of {total} culled: the test shows nothing");
        let ball = (Vec3::new(0.0, 1.2, 0.0), 1.0);
        let seen: Vec<bool> = faces.iter().map(|&m| sphere_in_frustum(m, ball.0, ball.1)).collect();
        assert_eq!(seen, [false, false, false, true, false, false], "caustic_sphere's ball seen from its light");
    }
}
