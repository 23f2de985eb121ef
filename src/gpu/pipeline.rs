//! Pipeline layouts, graphics pipelines (for explicit render passes) and compute pipelines.
use std::sync::Arc;

use ash::vk;

use super::context::GpuContext;
use super::error::{GpuResult, VkContext};
use super::{DescriptorSetLayout, RenderPass};

struct PipelineLayout {
    ctx: Arc<GpuContext>,
    pub(crate) raw: vk::PipelineLayout,
}

impl PipelineLayout {
    /// Push constants are visible to every stage; lavapipe allows 128 bytes.
    fn new(ctx: &Arc<GpuContext>, name: &str, sets: &[&DescriptorSetLayout], push_bytes: u32) -> GpuResult<Self> {
        let raw_sets: Vec<_> = sets.iter().map(|s| s.raw).collect();
        let ranges = [vk::PushConstantRange { stage_flags: vk::ShaderStageFlags::ALL, offset: 0, size: push_bytes }];
        let mut info = vk::PipelineLayoutCreateInfo::default().set_layouts(&raw_sets);
        if push_bytes > 0 {
            info = info.push_constant_ranges(&ranges);
        }
        // SAFETY: valid create info.
        let raw = unsafe { ctx.raw().create_pipeline_layout(&info, None) }.vk("vkCreatePipelineLayout")?;
        ctx.set_name(raw, name);
        Ok(PipelineLayout { ctx: ctx.clone(), raw })
    }
}

impl Drop for PipelineLayout {
    fn drop(&mut self) {
        // SAFETY: dropped with the renderer after the device is idle.
        unsafe { self.ctx.raw().destroy_pipeline_layout(self.raw, None) };
    }
}

/// Vertex input of a graphics pipeline.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum VertexLayout {
    /// No vertex buffers (full-screen triangle, points generated from gl_VertexIndex).
    None,
    /// `crate::renderer::Vertex`: position vec3, normal vec3, checker uv vec2 (32 bytes).
    Mesh,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Blend {
    Off,
    Additive,
}

#[derive(Clone, Copy, Debug)]
pub struct DepthState {
    pub test: bool,
    pub write: bool,
    pub compare: vk::CompareOp,
}

impl DepthState {
    pub const OFF: DepthState = DepthState { test: false, write: false, compare: vk::CompareOp::ALWAYS };
    /// prism uses reversed Z (1 at the near plane, 0 at infinity) for precision across scene
    /// scales from 1e-3 to 1e4, so nearer means greater.
    pub const REVERSED_Z: DepthState = DepthState { test: true, write: true, compare: vk::CompareOp::GREATER };
    /// Ordinary Z for light-space maps whose far plane is bounded by the scene.
    pub const LESS: DepthState = DepthState { test: true, write: true, compare: vk::CompareOp::LESS };
}

pub struct GraphicsPipelineDesc<'a> {
    pub name: &'a str,
    pub vertex_shader: &'a str,
    pub fragment_shader: &'a str,
    pub vertex: VertexLayout,
    pub topology: vk::PrimitiveTopology,
    pub cull: vk::CullModeFlags,
    pub depth: DepthState,
    /// One entry per colour attachment of the render pass.
    pub blend: &'a [Blend],
    /// Specialisation constants with ids 0, 1, ... (u32 each), for both stages.
    pub specialization: &'a [u32],
}

impl<'a> GraphicsPipelineDesc<'a> {
    /// One full-screen triangle (common/fullscreen.vert) into one colour target, no depth.
    pub fn fullscreen(name: &'a str, fragment_shader: &'a str) -> Self {
        GraphicsPipelineDesc {
            name,
            vertex_shader: "common/fullscreen.vert",
            fragment_shader,
            vertex: VertexLayout::None,
            topology: vk::PrimitiveTopology::TRIANGLE_LIST,
            cull: vk::CullModeFlags::NONE,
            depth: DepthState::OFF,
            blend: &[Blend::Off],
            specialization: &[],
        }
    }

    /// The scene's meshes as triangles, unculled: quads are one-sided and cameras, lights
    /// and reference points may sit on either side of a surface.
    pub fn mesh(name: &'a str, vertex_shader: &'a str, fragment_shader: &'a str, depth: DepthState) -> Self {
        GraphicsPipelineDesc {
            vertex_shader,
            vertex: VertexLayout::Mesh,
            depth,
            ..Self::fullscreen(name, fragment_shader)
        }
    }
}

pub struct GraphicsPipeline {
    ctx: Arc<GpuContext>,
    pub(crate) raw: vk::Pipeline,
    pub(crate) layout: vk::PipelineLayout,
    /// The pipeline's own layout (its fields drop after `Drop::drop` destroyed the pipeline).
    _layout: PipelineLayout,
}

fn shader_module(ctx: &GpuContext, path: &str) -> GpuResult<vk::ShaderModule> {
    let code = ctx.shader(path)?;
    let info = vk::ShaderModuleCreateInfo::default().code(&code);
    // SAFETY: code is SPIR-V compiled by shaderc, at build time or by the hot reload.
    let m = unsafe { ctx.raw().create_shader_module(&info, None) }.vk("vkCreateShaderModule")?;
    ctx.set_name(m, path);
    Ok(m)
}

impl GraphicsPipeline {
    /// A pipeline with a layout of its own: descriptor set layouts `sets` (set 0, 1, ...) and
    /// `push_bytes` of push constants.
    pub fn new(
        ctx: &Arc<GpuContext>,
        desc: &GraphicsPipelineDesc<'_>,
        sets: &[&DescriptorSetLayout],
        push_bytes: u32,
        pass: &RenderPass,
    ) -> GpuResult<Self> {
        let layout = PipelineLayout::new(ctx, desc.name, sets, push_bytes)?;
        let vs = shader_module(ctx, desc.vertex_shader)?;
        let fs = shader_module(ctx, desc.fragment_shader)?;
        let spec_entries: Vec<_> = (0..desc.specialization.len() as u32)
            .map(|i| vk::SpecializationMapEntry { constant_id: i, offset: i * 4, size: 4 })
            .collect();
        let spec_data: &[u8] = bytemuck::cast_slice(desc.specialization);
        let spec = vk::SpecializationInfo::default().map_entries(&spec_entries).data(spec_data);
        let stages = [
            vk::PipelineShaderStageCreateInfo::default()
                .stage(vk::ShaderStageFlags::VERTEX)
                .module(vs)
                .name(c"main")
                .specialization_info(&spec),
            vk::PipelineShaderStageCreateInfo::default()
                .stage(vk::ShaderStageFlags::FRAGMENT)
                .module(fs)
                .name(c"main")
                .specialization_info(&spec),
        ];
        let bindings =
            [vk::VertexInputBindingDescription { binding: 0, stride: 32, input_rate: vk::VertexInputRate::VERTEX }];
        let attributes = [
            vk::VertexInputAttributeDescription {
                location: 0,
                binding: 0,
                format: vk::Format::R32G32B32_SFLOAT,
                offset: 0,
            },
            vk::VertexInputAttributeDescription {
                location: 1,
                binding: 0,
                format: vk::Format::R32G32B32_SFLOAT,
                offset: 12,
            },
            vk::VertexInputAttributeDescription {
                location: 2,
                binding: 0,
                format: vk::Format::R32G32_SFLOAT,
                offset: 24,
            },
        ];
        let vertex_input = match desc.vertex {
            VertexLayout::None => vk::PipelineVertexInputStateCreateInfo::default(),
            VertexLayout::Mesh => vk::PipelineVertexInputStateCreateInfo::default()
                .vertex_binding_descriptions(&bindings)
                .vertex_attribute_descriptions(&attributes),
        };
        let input_assembly = vk::PipelineInputAssemblyStateCreateInfo::default().topology(desc.topology);
        let viewport = vk::PipelineViewportStateCreateInfo::default().viewport_count(1).scissor_count(1);
        let raster = vk::PipelineRasterizationStateCreateInfo::default()
            .polygon_mode(vk::PolygonMode::FILL)
            .cull_mode(desc.cull)
            .front_face(vk::FrontFace::COUNTER_CLOCKWISE)
            .line_width(1.0);
        let multisample =
            vk::PipelineMultisampleStateCreateInfo::default().rasterization_samples(vk::SampleCountFlags::TYPE_1);
        let depth = vk::PipelineDepthStencilStateCreateInfo::default()
            .depth_test_enable(desc.depth.test)
            .depth_write_enable(desc.depth.write)
            .depth_compare_op(desc.depth.compare);
        let blends: Vec<_> = desc
            .blend
            .iter()
            .map(|b| match b {
                Blend::Off => {
                    vk::PipelineColorBlendAttachmentState::default().color_write_mask(vk::ColorComponentFlags::RGBA)
                }
                Blend::Additive => vk::PipelineColorBlendAttachmentState::default()
                    .blend_enable(true)
                    .src_color_blend_factor(vk::BlendFactor::ONE)
                    .dst_color_blend_factor(vk::BlendFactor::ONE)
                    .color_blend_op(vk::BlendOp::ADD)
                    .src_alpha_blend_factor(vk::BlendFactor::ONE)
                    .dst_alpha_blend_factor(vk::BlendFactor::ONE)
                    .alpha_blend_op(vk::BlendOp::ADD)
                    .color_write_mask(vk::ColorComponentFlags::RGBA),
            })
            .collect();
        let blend = vk::PipelineColorBlendStateCreateInfo::default().attachments(&blends);
        let dynamic_states = [vk::DynamicState::VIEWPORT, vk::DynamicState::SCISSOR];
        let dynamic = vk::PipelineDynamicStateCreateInfo::default().dynamic_states(&dynamic_states);
        let info = vk::GraphicsPipelineCreateInfo::default()
            .stages(&stages)
            .vertex_input_state(&vertex_input)
            .input_assembly_state(&input_assembly)
            .viewport_state(&viewport)
            .rasterization_state(&raster)
            .multisample_state(&multisample)
            .depth_stencil_state(&depth)
            .color_blend_state(&blend)
            .dynamic_state(&dynamic)
            .layout(layout.raw)
            .render_pass(pass.raw)
            .subpass(0);
        // SAFETY: every referenced state struct lives until the call returns.
        let result = unsafe { ctx.raw().create_graphics_pipelines(vk::PipelineCache::null(), &[info], None) };
        // SAFETY: modules are no longer needed once the pipeline exists (or failed).
        unsafe {
            ctx.raw().destroy_shader_module(vs, None);
            ctx.raw().destroy_shader_module(fs, None);
        }
        let raw = result.map_err(|(_, e)| e).vk("vkCreateGraphicsPipelines")?[0];
        ctx.set_name(raw, desc.name);
        Ok(GraphicsPipeline { ctx: ctx.clone(), raw, layout: layout.raw, _layout: layout })
    }
}

impl Drop for GraphicsPipeline {
    fn drop(&mut self) {
        // SAFETY: dropped with the renderer after the device is idle.
        unsafe { self.ctx.raw().destroy_pipeline(self.raw, None) };
    }
}

pub struct ComputePipeline {
    ctx: Arc<GpuContext>,
    pub(crate) raw: vk::Pipeline,
    pub(crate) layout: vk::PipelineLayout,
    _layout: PipelineLayout,
}

impl ComputePipeline {
    /// As [`GraphicsPipeline::new`]: a compute pipeline with a layout of its own.
    pub fn new(
        ctx: &Arc<GpuContext>,
        name: &str,
        shader: &str,
        sets: &[&DescriptorSetLayout],
        push_bytes: u32,
        specialization: &[u32],
    ) -> GpuResult<Self> {
        let layout = PipelineLayout::new(ctx, name, sets, push_bytes)?;
        let module = shader_module(ctx, shader)?;
        let spec_entries: Vec<_> = (0..specialization.len() as u32)
            .map(|i| vk::SpecializationMapEntry { constant_id: i, offset: i * 4, size: 4 })
            .collect();
        let spec =
            vk::SpecializationInfo::default().map_entries(&spec_entries).data(bytemuck::cast_slice(specialization));
        let stage = vk::PipelineShaderStageCreateInfo::default()
            .stage(vk::ShaderStageFlags::COMPUTE)
            .module(module)
            .name(c"main")
            .specialization_info(&spec);
        let info = vk::ComputePipelineCreateInfo::default().stage(stage).layout(layout.raw);
        // SAFETY: valid create info.
        let result = unsafe { ctx.raw().create_compute_pipelines(vk::PipelineCache::null(), &[info], None) };
        // SAFETY: module no longer needed.
        unsafe { ctx.raw().destroy_shader_module(module, None) };
        let raw = result.map_err(|(_, e)| e).vk("vkCreateComputePipelines")?[0];
        ctx.set_name(raw, name);
        Ok(ComputePipeline { ctx: ctx.clone(), raw, layout: layout.raw, _layout: layout })
    }
}

impl Drop for ComputePipeline {
    fn drop(&mut self) {
        // SAFETY: dropped with the renderer after the device is idle.
        unsafe { self.ctx.raw().destroy_pipeline(self.raw, None) };
    }
}
