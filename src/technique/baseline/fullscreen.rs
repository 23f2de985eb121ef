//! The shape shared by full-screen passes: one triangle, a fragment shader reading set 0
//! (frame) and a set 1 of its own, writing one colour target. Deferred shading, the
//! specular baseline and the tone map are each this plus their own reads.
use std::sync::Arc;

use glam::Vec3;

use crate::frame::targets::Targets;
use crate::gpu::{
    vk, Access, Blend, Clear, Cmd, DescriptorSet, DescriptorSetLayout, GpuContext, GpuResult, GraphicsPipeline,
    GraphicsPipelineDesc, Image, RenderPass, RenderTarget, Specs,
};
use crate::graph::{Bindings, BoundSet, Frame, ImageId};
use crate::shader_structs::CoverPush;
use crate::technique::FrameInputs;

pub struct FullscreenPass {
    name: &'static str,
    target: RenderTarget,
    set: BoundSet,
    pipeline: GraphicsPipeline,
    clear: bool,
    target_id: ImageId,
    /// Shade only these objects' pixels when their meshes can be drawn ([`Cover`]).
    cover: Option<Cover>,
}

/// Shading limited to some objects' pixels. A pass that shades only the pixels of certain
/// materials (a refraction pass: the dielectrics') need not run its fragment shader over the
/// whole image: for each of those objects it draws an octagon around the outline of the
/// object's bounding sphere (glsl/common/cover.vert) instead of one full-screen triangle, so
/// that only the pixels inside that outline, and a thin margin, are shaded, with the same
/// fragment shader and the same `in_uv`. The fragment shader still discards what the
/// G-buffer says is not its material, so the image is the full-screen pass's.
///
/// Seen from the eye at distance d from the centre of a sphere of radius r, the sphere's
/// outline is the circle of radius r sqrt(d^2 - r^2) / d around the point
/// eye + (centre - eye) (1 - r^2 / d^2), in the plane normal to the line of sight; the
/// octagon circumscribes that circle (corners 1 / cos(pi / 8) = 1.082 times its radius away),
/// so its image circumscribes the outline, at most 5.5% more area (8 tan(pi / 8) / pi).
/// A flat proxy rather than the object's mesh: on a CPU device rasterizing the mesh again
/// (16k triangles for sphere_env's ball) costs as much as the G-buffer pass, and a CPU
/// rasterizer shades whole 4x4 blocks of every triangle, so few large triangles waste least.
/// When the eye is inside a bounding sphere, or a corner is behind the camera's plane (its
/// clip position cannot be divided by w), the pass falls back to the full-screen triangle
/// for that frame.
pub struct Cover {
    pipeline: GraphicsPipeline,
    objects: Vec<usize>,
}

/// How far the octagon's corners are from its centre, in radii of the circle it
/// circumscribes: 1 / cos(pi / 8).
pub const PROXY_SCALE: f32 = 1.082_392_2;

impl Cover {
    /// The cover of `objects` (indices into the scene's objects) for a pass with
    /// `fragment_shader`, `layouts` and `render_pass`. `None` without objects.
    #[allow(clippy::too_many_arguments)] // One pipeline's worth of state, as the pass that owns it has.
    pub fn new(
        ctx: &Arc<GpuContext>,
        name: &str,
        fragment_shader: &str,
        specialization: Specs<'_>,
        blend: &[Blend],
        layouts: &[&DescriptorSetLayout],
        render_pass: &RenderPass,
        objects: Vec<usize>,
    ) -> GpuResult<Option<Cover>> {
        if objects.is_empty() {
            return Ok(None);
        }
        let pipeline = GraphicsPipeline::new(
            ctx,
            &GraphicsPipelineDesc {
                vertex_shader: "common/cover.vert",
                blend,
                specialization,
                ..GraphicsPipelineDesc::fullscreen(name, fragment_shader)
            },
            layouts,
            std::mem::size_of::<CoverPush>() as u32,
            render_pass,
        )?;
        Ok(Some(Cover { pipeline, objects }))
    }

    /// Each object's octagon this frame, or `None` if one cannot be drawn (the eye inside
    /// its bounding sphere, or a corner not in front of the camera).
    pub fn octagons(&self, inputs: &FrameInputs<'_>) -> Option<Vec<CoverPush>> {
        self.objects.iter().map(|&i| octagon(*inputs.object_bounds.get(i)?, inputs.eye, inputs.forward)).collect()
    }

    /// Draw `octagons` with `sets` bound (inside the pass's render pass).
    pub fn draw(&self, cmd: &Cmd, sets: &[DescriptorSet], octagons: &[CoverPush]) {
        cmd.bind_graphics(&self.pipeline, sets);
        for o in octagons {
            cmd.push_graphics(&self.pipeline, o);
            cmd.draw(18, 1);
        }
    }
}

/// The octagon around the outline of the sphere `(centre, radius)` seen from `eye` (see
/// [`Cover`]); `None` when the eye is inside the sphere or a corner is not in front of the
/// camera.
pub fn octagon((centre, radius): (Vec3, f32), eye: Vec3, forward: Vec3) -> Option<CoverPush> {
    let to = centre - eye;
    let d = to.length();
    // A relative margin for rounding: a sphere grazing the eye is drawn full-screen.
    if d.is_nan() || d <= radius * (1.0 + 1e-3) {
        return None;
    }
    let w = to / d;
    let k = 1.0 - (radius / d) * (radius / d);
    let middle = eye + to * k;
    let circle = radius * k.sqrt();
    let u = w.any_orthonormal_vector();
    let v = w.cross(u);
    let (u, v) = (u * circle * PROXY_SCALE, v * circle * PROXY_SCALE);
    let corners = (0..8).map(|c| {
        let a = c as f32 * std::f32::consts::FRAC_PI_4;
        middle + a.cos() * u + a.sin() * v
    });
    // In front of the camera, with a margin for the rounding of w on the GPU.
    let nearest = corners.map(|p| (p - eye).dot(forward)).fold(f32::INFINITY, f32::min);
    (nearest > 1e-4 * d).then(|| CoverPush {
        centre: middle.extend(1.0).to_array(),
        u: u.extend(0.0).to_array(),
        v: v.extend(0.0).to_array(),
    })
}

pub struct FullscreenDesc<'a> {
    /// Pass name (snake_case; timing, label and golden-image name).
    pub name: &'static str,
    /// Fragment shader under glsl/ (the vertex shader is common/fullscreen.vert).
    pub fragment_shader: &'a str,
    pub target: (&'a Image, ImageId),
    /// Clear the target first (true) or keep what earlier passes wrote (false).
    pub clear: bool,
    /// Specialisation constants of the fragment shader, by name.
    pub specialization: Specs<'a>,
    /// Add to what the target holds (a light added after shading) instead of overwriting it.
    pub additive: bool,
}

impl<'a> FullscreenDesc<'a> {
    /// A pass composited into the HDR image: it keeps what earlier passes wrote there and
    /// overwrites the pixels its shader writes (a specular object, a volume, a receiver).
    pub fn over_hdr(
        name: &'static str,
        fragment_shader: &'a str,
        targets: &'a Targets,
        specialization: Specs<'a>,
    ) -> Self {
        FullscreenDesc {
            name,
            fragment_shader,
            target: (&targets.hdr, targets.hdr_id),
            clear: false,
            specialization,
            additive: false,
        }
    }
}

/// Set 1 of a full-screen pass: fragment-stage resources.
pub fn fragment_set<'a>() -> Bindings<'a> {
    Bindings::new(vk::ShaderStageFlags::FRAGMENT)
}

impl FullscreenPass {
    /// The pass of `desc` with `set` as its set 1 (its tracked resources are the pass's reads).
    pub fn new(
        ctx: &Arc<GpuContext>,
        desc: &FullscreenDesc<'_>,
        set: Bindings<'_>,
        frame_layout: &DescriptorSetLayout,
    ) -> GpuResult<Self> {
        let (target, target_id) = desc.target;
        let render_target = RenderTarget::new(ctx, desc.name, &[target], None, desc.clear)?;
        let set = set.build(ctx, desc.name)?;
        let pipeline = GraphicsPipeline::new(
            ctx,
            &GraphicsPipelineDesc {
                specialization: desc.specialization,
                blend: if desc.additive { &[Blend::Additive] } else { &[Blend::Off] },
                ..GraphicsPipelineDesc::fullscreen(desc.name, desc.fragment_shader)
            },
            &[frame_layout, set.layout()],
            0,
            &render_target.pass,
        )?;
        Ok(FullscreenPass {
            name: desc.name,
            target: render_target,
            set,
            pipeline,
            clear: desc.clear,
            target_id,
            cover: None,
        })
    }

    /// [`FullscreenPass::new`] shading only the pixels of `objects` when it can ([`Cover`];
    /// record it with [`FullscreenPass::record_covering`]).
    pub fn covering(
        ctx: &Arc<GpuContext>,
        desc: &FullscreenDesc<'_>,
        set: Bindings<'_>,
        frame_layout: &DescriptorSetLayout,
        objects: Vec<usize>,
    ) -> GpuResult<Self> {
        let mut pass = Self::new(ctx, desc, set, frame_layout)?;
        pass.cover = Cover::new(
            ctx,
            desc.name,
            desc.fragment_shader,
            desc.specialization,
            &[Blend::Off],
            &[frame_layout, pass.set.layout()],
            &pass.target.pass,
            objects,
        )?;
        Ok(pass)
    }

    /// [`FullscreenPass::record`], drawing the covered objects' meshes instead of the
    /// full-screen triangle where they can be ([`Cover::usable`]).
    pub fn record_covering<'a>(&'a self, frame: &mut Frame<'_, 'a>, inputs: &FrameInputs<'a>, reads: &[ImageId]) {
        let cover = self.cover.as_ref().and_then(|c| Some((c, c.octagons(inputs)?)));
        self.record_with(frame, inputs.frame_set, reads, cover);
    }

    /// Add the pass to `frame`: its set's reads, and `reads` of the frame set (set 0) in
    /// its fragment shader.
    pub fn record<'a>(&'a self, frame: &mut Frame<'_, 'a>, frame_set: DescriptorSet, reads: &[ImageId]) {
        self.record_with(frame, frame_set, reads, None);
    }

    fn record_with<'a>(
        &'a self,
        frame: &mut Frame<'_, 'a>,
        frame_set: DescriptorSet,
        reads: &[ImageId],
        cover: Option<(&'a Cover, Vec<CoverPush>)>,
    ) {
        let mut pass = frame.pass(self.name).uses(&self.set);
        for &id in reads {
            pass = pass.read(id, Access::FragmentSampled);
        }
        pass.write(self.target_id, Access::ColorAttachment).record(move |cmd| {
            let clear = if self.clear { Clear::Color([0.0; 4]) } else { Clear::None };
            cmd.in_target(&self.target, 0, &[clear], |cmd| match cover {
                Some((cover, octagons)) => cover.draw(cmd, &[frame_set, self.set.set()], &octagons),
                None => {
                    cmd.bind_graphics(&self.pipeline, &[frame_set, self.set.set()]);
                    cmd.draw(3, 1);
                }
            });
        });
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The octagon lies in the plane of the sphere's outline circle and every edge touches
    /// or clears that circle: each line from the eye through an edge's midpoint misses the
    /// sphere or grazes it.
    #[test]
    fn the_octagon_circumscribes_the_spheres_outline() {
        let (centre, radius, eye) = (Vec3::new(0.3, -0.2, 0.1), 0.7, Vec3::new(1.0, 2.0, 4.0));
        let forward = (centre - eye).normalize();
        let o = octagon((centre, radius), eye, forward).unwrap();
        let (m, u, v) = (Vec3::from_slice(&o.centre[..3]), Vec3::from_slice(&o.u[..3]), Vec3::from_slice(&o.v[..3]));
        for c in 0..8 {
            let corner = |k: i32| {
                let a = k as f32 * std::f32::consts::FRAC_PI_4;
                m + a.cos() * u + a.sin() * v
            };
            let mid = 0.5 * (corner(c) + corner(c + 1));
            let ray = (mid - eye).normalize();
            let closest = (centre - eye).dot(ray);
            let miss = ((centre - eye).length_squared() - closest * closest).sqrt();
            assert!((miss / radius - 1.0).abs() < 1e-4, "edge {c} passes {miss} from the centre");
        }
        assert!(octagon((centre, radius), centre + Vec3::X * 0.5 * radius, forward).is_none(), "eye inside");
        assert!(octagon((centre, radius), eye, -forward).is_none(), "behind the camera");
    }
}
