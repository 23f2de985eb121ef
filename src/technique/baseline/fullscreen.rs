//! The shape shared by full-screen passes: one triangle, a fragment shader reading set 0
//! (frame) and a set 1 of its own, writing one colour target. Deferred shading, the
//! specular baseline and the tone map are each this plus their own reads.
use std::sync::Arc;

use glam::{Mat4, Vec2, Vec3};

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
/// for that frame. Each octagon is also scissored to the rectangle its object's bounding
/// box projects into ([`box_scissor`]), which clips the octagon where the sphere holds much
/// that the box does not (the corners of an elongated object's sphere).
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

    /// Each object's octagon this frame with its scissor, or `None` if one cannot be drawn
    /// (the eye inside its bounding sphere, or a corner not in front of the camera).
    pub fn octagons(&self, inputs: &FrameInputs<'_>) -> Option<Vec<CoverDraw>> {
        let (width, height) = (inputs.targets.width, inputs.targets.height);
        let full = vk::Rect2D { offset: vk::Offset2D::default(), extent: vk::Extent2D { width, height } };
        let mut draws = Vec::new();
        for &i in &self.objects {
            let push = octagon(*inputs.object_bounds.get(i)?, inputs.eye, inputs.forward)?;
            let scissor = match inputs.object_boxes.get(i) {
                Some(&b) => match box_scissor(b, inputs.view_proj, width, height) {
                    Some(Some(rect)) => rect,
                    // Wholly outside the frame: no pixel to shade.
                    Some(None) => continue,
                    None => full,
                },
                None => full,
            };
            draws.push(CoverDraw { push, scissor });
        }
        Some(draws)
    }

    /// Draw `octagons` with `sets` bound (inside the pass's render pass); the scissor is the
    /// whole target again afterwards.
    pub fn draw(&self, cmd: &Cmd, sets: &[DescriptorSet], octagons: &[CoverDraw], extent: vk::Extent2D) {
        cmd.bind_graphics(&self.pipeline, sets);
        for o in octagons {
            cmd.set_scissor(o.scissor);
            cmd.push_graphics(&self.pipeline, &o.push);
            cmd.draw(18, 1);
        }
        cmd.set_scissor(vk::Rect2D { offset: vk::Offset2D::default(), extent });
    }
}

/// One object's octagon and the pixel rectangle its bounding box projects into: the octagon
/// circumscribes the bounding sphere, which for an elongated or hollow-cornered object
/// holds much that its box's image does not (bunny_env's bunny: the octagon covers 78% of
/// the frame, both together 67%).
pub struct CoverDraw {
    push: CoverPush,
    scissor: vk::Rect2D,
}

/// The pixels of a `width` x `height` target that the box (centre, half extents) projects
/// into through `view_proj`: the rectangle around its eight corners' images, widened to
/// whole pixels and by one more on every side for rounding. `Some(None)` when the rectangle
/// misses the target; `None` when a corner is not in front of the camera (its clip position
/// cannot be divided by w), where no rectangle is known. The convex hull of the corners'
/// images holds the box's image, and so the object's.
pub fn box_scissor(
    (centre, half): (Vec3, Vec3),
    view_proj: Mat4,
    width: u32,
    height: u32,
) -> Option<Option<vk::Rect2D>> {
    let (mut lo, mut hi) = (Vec2::splat(f32::INFINITY), Vec2::splat(f32::NEG_INFINITY));
    for k in 0..8 {
        let sign = Vec3::new([-1.0, 1.0][k & 1], [-1.0, 1.0][(k >> 1) & 1], [-1.0, 1.0][k >> 2]);
        let clip = view_proj * (centre + sign * half).extend(1.0);
        // A margin for the rounding of w, as the octagon's (`octagon`).
        if clip.w.is_nan() || clip.w <= 1e-6 * clip.truncate().length().max(1.0) {
            return None;
        }
        // uv = ndc / 2 + 1/2, (0, 0) at the top-left pixel corner (common/cover.vert).
        let pixel = (Vec2::new(clip.x, clip.y) / clip.w * 0.5 + 0.5) * Vec2::new(width as f32, height as f32);
        lo = lo.min(pixel);
        hi = hi.max(pixel);
    }
    let size = Vec2::new(width as f32, height as f32);
    let (lo, hi) = ((lo - 1.0).floor().max(Vec2::ZERO), (hi + 1.0).ceil().min(size));
    if !(hi.x > lo.x && hi.y > lo.y) {
        return Some(None);
    }
    Some(Some(vk::Rect2D {
        offset: vk::Offset2D { x: lo.x as i32, y: lo.y as i32 },
        extent: vk::Extent2D { width: (hi.x - lo.x) as u32, height: (hi.y - lo.y) as u32 },
    }))
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
        cover: Option<(&'a Cover, Vec<CoverDraw>)>,
    ) {
        let mut pass = frame.pass(self.name).uses(&self.set);
        for &id in reads {
            pass = pass.read(id, Access::FragmentSampled);
        }
        pass.write(self.target_id, Access::ColorAttachment).record(move |cmd| {
            let clear = if self.clear { Clear::Color([0.0; 4]) } else { Clear::None };
            cmd.in_target(&self.target, 0, &[clear], |cmd| match cover {
                Some((cover, octagons)) => {
                    cover.draw(cmd, &[frame_set, self.set.set()], &octagons, self.target.extent())
                }
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

    /// The scissor holds every corner's pixel (so the box's image and the object's), widened
    /// by at most two pixels per side; a box beside the frame gives no rectangle to draw, one
    /// with a corner behind the camera no rectangle at all (the octagon's alone then).
    #[test]
    fn the_scissor_holds_the_boxs_image() {
        let (w, h) = (200, 150);
        let eye = Vec3::new(0.0, 0.0, 4.0);
        let view = Mat4::look_at_rh(eye, Vec3::ZERO, Vec3::Y);
        let proj = crate::renderer::camera_projection(40.0, w as f32 / h as f32, 1e-3);
        let view_proj = proj * view;
        let b = (Vec3::new(0.4, -0.3, 0.2), Vec3::new(0.5, 0.3, 0.7));
        let rect = box_scissor(b, view_proj, w, h).unwrap().unwrap();
        let (x0, y0) = (rect.offset.x as f32, rect.offset.y as f32);
        let (x1, y1) = (x0 + rect.extent.width as f32, y0 + rect.extent.height as f32);
        let (mut lo, mut hi) = (Vec2::splat(f32::INFINITY), Vec2::splat(f32::NEG_INFINITY));
        for k in 0..8 {
            let sign = Vec3::new([-1.0, 1.0][k & 1], [-1.0, 1.0][(k >> 1) & 1], [-1.0, 1.0][k >> 2]);
            let clip = view_proj * (b.0 + sign * b.1).extend(1.0);
            let p = (Vec2::new(clip.x, clip.y) / clip.w * 0.5 + 0.5) * Vec2::new(w as f32, h as f32);
            assert!(p.x >= x0 && p.x <= x1 && p.y >= y0 && p.y <= y1, "corner {k} at {p} outside {rect:?}");
            lo = lo.min(p);
            hi = hi.max(p);
        }
        assert!(lo.x - x0 <= 2.0 && lo.y - y0 <= 2.0 && x1 - hi.x <= 2.0 && y1 - hi.y <= 2.0, "{rect:?}");
        // Far to the side: nothing of it is in the frame.
        assert_eq!(box_scissor((Vec3::new(40.0, 0.0, 0.0), Vec3::splat(0.5)), view_proj, w, h), Some(None));
        // Around the eye: a corner behind the camera.
        assert_eq!(box_scissor((eye, Vec3::splat(0.5)), view_proj, w, h), None);
    }
}
