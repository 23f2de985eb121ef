//! The shape shared by full-screen passes: one triangle, a fragment shader reading set 0
//! (frame) and a set 1 of sampled images, writing one colour target. Deferred shading, the
//! specular baseline and the tone map are each this plus their own reads.
use std::sync::Arc;

use crate::gpu::{
    vk, Access, Attachment, Blend, Buffer, Clear, DepthState, DescriptorSet, DescriptorSetLayout, DescriptorWrite,
    Framebuffer, GpuContext, GpuResult, GraphicsPipeline, GraphicsPipelineDesc, Image, PipelineLayout, RenderPass,
    RenderPassDesc, Sampler, VertexLayout,
};
use crate::graph::{BufferId, Frame, ImageId};

pub struct FullscreenPass {
    name: &'static str,
    render_pass: RenderPass,
    _set_layout: DescriptorSetLayout,
    set: DescriptorSet,
    _layout: PipelineLayout,
    pipeline: GraphicsPipeline,
    framebuffer: Framebuffer,
    clear: bool,
    target: ImageId,
}

pub struct FullscreenDesc<'a> {
    /// Pass name (snake_case; timing, label and golden-image name).
    pub name: &'static str,
    /// Fragment shader under glsl/ (the vertex shader is common/fullscreen.vert).
    pub fragment_shader: &'a str,
    /// Set-1 inputs: (binding, image), sampled with `sampler`.
    pub inputs: &'a [(u32, &'a Image)],
    pub target: (&'a Image, ImageId),
    /// Clear the target first (true) or keep what earlier passes wrote (false).
    pub clear: bool,
    /// Specialisation constants 0, 1, ... of the fragment shader.
    pub specialization: &'a [u32],
}

impl FullscreenPass {
    pub fn new(
        ctx: &Arc<GpuContext>,
        desc: &FullscreenDesc<'_>,
        frame_layout: &DescriptorSetLayout,
        sampler: &Sampler,
    ) -> GpuResult<Self> {
        Self::with_buffers(ctx, desc, &[], frame_layout, sampler)
    }

    /// As [`Self::new`], with storage buffers (binding, buffer) in set 1 besides the images.
    pub fn with_buffers(
        ctx: &Arc<GpuContext>,
        desc: &FullscreenDesc<'_>,
        buffers: &[(u32, &Buffer)],
        frame_layout: &DescriptorSetLayout,
        sampler: &Sampler,
    ) -> GpuResult<Self> {
        let (target, target_id) = desc.target;
        let render_pass = RenderPass::new(
            ctx,
            desc.name,
            &RenderPassDesc {
                colors: vec![Attachment { format: target.format(), clear: desc.clear }],
                depth: None,
                depth_read_only: false,
            },
        )?;
        let bindings: Vec<_> = desc
            .inputs
            .iter()
            .map(|&(b, _)| (b, vk::DescriptorType::COMBINED_IMAGE_SAMPLER, vk::ShaderStageFlags::FRAGMENT))
            .chain(
                buffers.iter().map(|&(b, _)| (b, vk::DescriptorType::STORAGE_BUFFER, vk::ShaderStageFlags::FRAGMENT)),
            )
            .collect();
        let set_layout = DescriptorSetLayout::new(ctx, desc.name, &bindings, 1)?;
        let writes: Vec<_> = desc
            .inputs
            .iter()
            .map(|&(b, image)| {
                // The layout the graph gives a sampled image (Access::FragmentSampled).
                let layout = Access::FragmentSampled.info(image.aspect().contains(vk::ImageAspectFlags::DEPTH)).layout;
                DescriptorWrite::Sampled(b, image.view(), sampler, layout)
            })
            .chain(buffers.iter().map(|&(b, buffer)| DescriptorWrite::Storage(b, buffer)))
            .collect();
        let set = set_layout.allocate(desc.name, &writes)?;
        let layout = PipelineLayout::new(ctx, desc.name, &[frame_layout, &set_layout], 0)?;
        let pipeline = GraphicsPipeline::new(
            ctx,
            &GraphicsPipelineDesc {
                name: desc.name,
                vertex_shader: "common/fullscreen.vert",
                fragment_shader: desc.fragment_shader,
                vertex: VertexLayout::None,
                topology: vk::PrimitiveTopology::TRIANGLE_LIST,
                cull: vk::CullModeFlags::NONE,
                depth: DepthState::OFF,
                blend: &[Blend::Off],
                specialization: desc.specialization,
            },
            &layout,
            &render_pass,
        )?;
        let framebuffer = Framebuffer::new(
            ctx,
            desc.name,
            &render_pass,
            &[target.view()],
            vk::Extent2D { width: target.desc.width, height: target.desc.height },
        )?;
        Ok(FullscreenPass {
            name: desc.name,
            render_pass,
            _set_layout: set_layout,
            set,
            _layout: layout,
            pipeline,
            framebuffer,
            clear: desc.clear,
            target: target_id,
        })
    }

    /// Add the pass to `frame`, sampling `reads` in its fragment shader.
    pub fn record<'a>(&'a self, frame: &mut Frame<'_, 'a>, frame_set: DescriptorSet, reads: &[ImageId]) {
        self.record_with(frame, frame_set, reads, &[]);
    }

    /// [`FullscreenPass::record`], also declaring `buffers` (the adaptive tone map declares
    /// its statistics' host read here, so that the graph makes them visible to the host).
    pub fn record_with<'a>(
        &'a self,
        frame: &mut Frame<'_, 'a>,
        frame_set: DescriptorSet,
        reads: &[ImageId],
        buffers: &[(BufferId, Access)],
    ) {
        let mut pass = frame.pass(self.name);
        for &id in reads {
            pass = pass.read(id, Access::FragmentSampled);
        }
        for &(id, access) in buffers {
            pass = pass.read_buffer(id, access);
        }
        pass.write(self.target, Access::ColorAttachment).record(move |cmd| {
            let clear = if self.clear { Clear::Color([0.0; 4]) } else { Clear::None };
            cmd.in_render_pass(&self.render_pass, &self.framebuffer, &[clear], |cmd| {
                cmd.bind_graphics(&self.pipeline, &[frame_set, self.set]);
                cmd.draw(3, 1);
            });
        });
    }
}
