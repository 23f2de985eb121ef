//! The shape shared by full-screen passes: one triangle, a fragment shader reading set 0
//! (frame) and a set 1 of its own, writing one colour target. Deferred shading, the
//! specular baseline and the tone map are each this plus their own reads.
use std::sync::Arc;

use glam::Vec3;

use crate::frame::targets::Targets;
use crate::gpu::{
    vk, Access, Blend, Buffer, Clear, Cmd, DescriptorSet, DescriptorSetLayout, GpuContext, GpuResult, GraphicsPipeline,
    GraphicsPipelineDesc, Image, RenderPass, RenderTarget, Specs, VertexLayout,
};
use crate::graph::{Bindings, BoundSet, Frame, ImageId};
use crate::shader_structs::{CoverPush, Vertex};
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
/// whole image: it draws, for each of those objects, a convex polyhedron around the object's
/// bounding sphere (glsl/common/cover.vert) instead of one full-screen triangle, so that only
/// the pixels inside the object's outline (and a thin margin) are shaded, with the same
/// fragment shader and the same `in_uv`. The fragment shader still discards what the
/// G-buffer says is not its material, so the image is the full-screen pass's.
///
/// A proxy rather than the object's own mesh: on a CPU device rasterizing the mesh again
/// (16k triangles for sphere_env's ball) costs as much as the G-buffer pass, while the
/// proxy's 320 triangles cost nothing. Its back faces are culled, so that every pixel inside
/// it is shaded once. When a proxy reaches behind the camera's plane its vertices cannot be
/// divided by w (cover.vert), and the pass falls back to the full-screen triangle for that
/// frame.
pub struct Cover {
    pipeline: GraphicsPipeline,
    proxy: Buffer,
    proxy_vertices: u32,
    objects: Vec<usize>,
}

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
        let vertices: Vec<Vertex> = proxy_sphere()
            .into_iter()
            .map(|p| Vertex { position: p.to_array(), normal: p.to_array(), checker_uv: [0.0; 2] })
            .collect();
        let proxy = Buffer::with_data(ctx, &format!("{name}_cover"), &vertices, vk::BufferUsageFlags::VERTEX_BUFFER)?;
        let pipeline = GraphicsPipeline::new(
            ctx,
            &GraphicsPipelineDesc {
                vertex_shader: "common/cover.vert",
                vertex: VertexLayout::Mesh,
                // The proxy is convex with its faces wound alike: either side covers its
                // outline once.
                cull: vk::CullModeFlags::BACK,
                blend,
                specialization,
                ..GraphicsPipelineDesc::fullscreen(name, fragment_shader)
            },
            layouts,
            std::mem::size_of::<CoverPush>() as u32,
            render_pass,
        )?;
        Ok(Some(Cover { pipeline, proxy, proxy_vertices: vertices.len() as u32, objects }))
    }

    /// Whether the proxies can be drawn this frame: each lies wholly in front of the
    /// camera's plane (then every vertex has w > 0).
    pub fn usable(&self, inputs: &FrameInputs<'_>) -> bool {
        self.objects.iter().all(|&i| {
            inputs.object_bounds.get(i).is_some_and(|&(centre, radius)| {
                // A relative margin for the rounding of w on the GPU.
                (centre - inputs.eye).dot(inputs.forward) > radius * PROXY_SCALE * (1.0 + 1e-3) + 1e-6
            })
        })
    }

    /// Draw each object's proxy with `sets` bound (inside the pass's render pass).
    pub fn draw(&self, cmd: &Cmd, sets: &[DescriptorSet], inputs_bounds: &[(Vec3, f32)]) {
        cmd.bind_graphics(&self.pipeline, sets);
        cmd.bind_vertex_buffer(&self.proxy);
        for &i in &self.objects {
            let (c, r) = inputs_bounds[i];
            cmd.push_graphics(&self.pipeline, &CoverPush { sphere: [c.x, c.y, c.z, r * PROXY_SCALE] });
            cmd.draw(self.proxy_vertices, 1);
        }
    }
}

/// How much larger than the sphere it bounds [`proxy_sphere`]'s polyhedron is drawn: the
/// reciprocal of the smallest distance from the centre to a face plane of the unit-vertex
/// polyhedron (0.9822 for the icosahedron subdivided twice), so that every face lies
/// outside the sphere. Checked by `proxy_circumscribes_the_unit_sphere`.
pub const PROXY_SCALE: f32 = 1.0 / 0.98;

/// A closed convex polyhedron with vertices on the unit sphere, as a triangle list wound
/// alike (counter-clockwise seen from outside): the icosahedron with each face split in
/// four twice, 320 triangles.
pub fn proxy_sphere() -> Vec<Vec3> {
    let t = (1.0 + 5f32.sqrt()) / 2.0;
    let v = [
        Vec3::new(-1.0, t, 0.0),
        Vec3::new(1.0, t, 0.0),
        Vec3::new(-1.0, -t, 0.0),
        Vec3::new(1.0, -t, 0.0),
        Vec3::new(0.0, -1.0, t),
        Vec3::new(0.0, 1.0, t),
        Vec3::new(0.0, -1.0, -t),
        Vec3::new(0.0, 1.0, -t),
        Vec3::new(t, 0.0, -1.0),
        Vec3::new(t, 0.0, 1.0),
        Vec3::new(-t, 0.0, -1.0),
        Vec3::new(-t, 0.0, 1.0),
    ]
    .map(Vec3::normalize);
    let faces = [
        [0, 11, 5],
        [0, 5, 1],
        [0, 1, 7],
        [0, 7, 10],
        [0, 10, 11],
        [1, 5, 9],
        [5, 11, 4],
        [11, 10, 2],
        [10, 7, 6],
        [7, 1, 8],
        [3, 9, 4],
        [3, 4, 2],
        [3, 2, 6],
        [3, 6, 8],
        [3, 8, 9],
        [4, 9, 5],
        [2, 4, 11],
        [6, 2, 10],
        [8, 6, 7],
        [9, 8, 1],
    ];
    let mut tris: Vec<[Vec3; 3]> = faces.iter().map(|f| [v[f[0]], v[f[1]], v[f[2]]]).collect();
    for _ in 0..2 {
        tris = tris
            .iter()
            .flat_map(|&[a, b, c]| {
                let (ab, bc, ca) = ((a + b).normalize(), (b + c).normalize(), (c + a).normalize());
                [[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]
            })
            .collect();
    }
    tris.into_iter()
        .flat_map(|[a, b, c]| {
            // Wind every face counter-clockwise seen from outside.
            if (b - a).cross(c - a).dot(a + b + c) < 0.0 {
                [a, c, b]
            } else {
                [a, b, c]
            }
        })
        .collect()
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
        FullscreenDesc { name, fragment_shader, target: (&targets.hdr, targets.hdr_id), clear: false, specialization }
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
        let cover = self.cover.as_ref().filter(|c| c.usable(inputs));
        self.record_with(frame, inputs.frame_set, reads, cover.map(|c| (c, inputs.object_bounds)));
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
        cover: Option<(&'a Cover, &'a [(Vec3, f32)])>,
    ) {
        let mut pass = frame.pass(self.name).uses(&self.set);
        for &id in reads {
            pass = pass.read(id, Access::FragmentSampled);
        }
        pass.write(self.target_id, Access::ColorAttachment).record(move |cmd| {
            let clear = if self.clear { Clear::Color([0.0; 4]) } else { Clear::None };
            cmd.in_target(&self.target, 0, &[clear], |cmd| match cover {
                Some((cover, bounds)) => cover.draw(cmd, &[frame_set, self.set.set()], bounds),
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

    /// Every face plane of the scaled proxy lies outside the unit sphere (so its outline
    /// contains the sphere's), by less than 3% (so it shades few pixels outside).
    #[test]
    fn proxy_circumscribes_the_unit_sphere() {
        let p = proxy_sphere();
        assert_eq!(p.len(), 320 * 3);
        let mut nearest = f32::INFINITY;
        for t in p.chunks_exact(3) {
            let n = (t[1] - t[0]).cross(t[2] - t[0]).normalize();
            assert!(n.dot(t[0] + t[1] + t[2]) > 0.0, "wound counter-clockwise seen from outside");
            nearest = nearest.min(n.dot(t[0]) * PROXY_SCALE);
        }
        assert!((1.0..1.03).contains(&nearest), "{nearest}");
    }
}
