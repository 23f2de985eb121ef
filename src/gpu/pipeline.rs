//! Pipeline layouts, graphics pipelines (for explicit render passes) and compute pipelines.
//!
//! Pipelines are cached by description, as render passes are: the context holds each live
//! pipeline weakly under the hash of everything it is made from (its shaders' SPIR-V, its
//! specialisation, its set layouts' bindings, its push-constant size, its fixed-function
//! state and its render pass's description). A technique re-created around new targets (a
//! resize) gets the pipelines of the one it replaces, which is still alive while the new one
//! is built; an edited shader has new SPIR-V, so the hot reload makes a new pipeline.
use std::hash::{Hash, Hasher};
use std::sync::Arc;

use ash::vk;

use super::context::GpuContext;
use super::error::{GpuError, GpuResult, VkContext};
use super::{DescriptorSetLayout, RenderPass, ShaderCode};

/// The value of a specialisation constant. Pipelines name their constants as the shader
/// declares them (`layout(constant_id = N) const uint NAME`, [`Specs`]) and the gpu layer
/// finds N, so Rust and GLSL never match positions by hand.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Spec {
    U32(u32),
    I32(i32),
    F32(f32),
    Bool(bool),
}

impl Spec {
    /// The GLSL type of a constant this value may set.
    fn glsl_type(self) -> &'static str {
        match self {
            Spec::U32(_) => "uint",
            Spec::I32(_) => "int",
            Spec::F32(_) => "float",
            Spec::Bool(_) => "bool",
        }
    }

    /// The 4 bytes of specialisation data (a `bool` is a VkBool32).
    fn bits(self) -> u32 {
        match self {
            Spec::U32(v) => v,
            Spec::I32(v) => v as u32,
            Spec::F32(v) => v.to_bits(),
            Spec::Bool(v) => u32::from(v),
        }
    }
}

/// Named specialisation constants of one pipeline, for all of its stages.
pub type Specs<'a> = &'a [(&'a str, Spec)];

/// Specialisation of the shaders `stages` (path, code) by `specs`: one data block and each
/// stage's map entries into it. A stage gets the constants its source declares; a name that
/// no stage declares, or of another type than the value, is an error naming the shaders.
fn specialize(
    stages: &[(&str, &ShaderCode)],
    specs: Specs<'_>,
) -> GpuResult<(Vec<u32>, Vec<Vec<vk::SpecializationMapEntry>>)> {
    let shaders = || stages.iter().map(|(path, _)| *path).collect::<Vec<_>>().join(" + ");
    let mut entries = vec![Vec::new(); stages.len()];
    for (i, &(name, value)) in specs.iter().enumerate() {
        let problem = |what: String| GpuError::Specialization(format!("{}: {name}: {what}", shaders()));
        if specs[..i].iter().any(|(n, _)| *n == name) {
            return Err(problem("set twice".into()));
        }
        let mut declared = false;
        for ((_, code), entries) in stages.iter().zip(&mut entries) {
            let Some(decl) = code.specs.iter().find(|d| d.name == name) else { continue };
            if decl.ty != value.glsl_type() {
                return Err(problem(format!("declared {}, set as {value:?}", decl.ty)));
            }
            entries.push(vk::SpecializationMapEntry { constant_id: decl.id, offset: 4 * i as u32, size: 4 });
            declared = true;
        }
        if !declared {
            let names: Vec<_> = stages.iter().flat_map(|(_, c)| c.specs.iter().map(|d| d.name.as_str())).collect();
            return Err(problem(format!("no such specialisation constant (declared: {})", names.join(", "))));
        }
    }
    Ok((specs.iter().map(|(_, v)| v.bits()).collect(), entries))
}

/// A pipeline and its layout, shared by every pipeline object of one description.
pub(crate) struct SharedPipeline {
    ctx: Arc<GpuContext>,
    raw: vk::Pipeline,
    // Destroyed after the pipeline (fields drop after `Drop::drop`).
    layout: PipelineLayout,
}

/// The hash of what a pipeline is made from, besides its fixed-function state `state`.
fn pipeline_key(
    name: &str,
    stages: &[(&str, &ShaderCode)],
    specialization: &(Vec<u32>, Vec<Vec<vk::SpecializationMapEntry>>),
    sets: &[&DescriptorSetLayout],
    push_bytes: u32,
    state: impl Hash,
) -> u64 {
    let mut h = std::collections::hash_map::DefaultHasher::new();
    name.hash(&mut h);
    for (path, code) in stages {
        (path, &code.words).hash(&mut h);
    }
    let (data, entries) = specialization;
    data.hash(&mut h);
    for e in entries.iter().flatten() {
        (e.constant_id, e.offset, e.size).hash(&mut h);
    }
    for set in sets {
        set.bindings.hash(&mut h);
    }
    (push_bytes, state).hash(&mut h);
    h.finish()
}

/// The live pipeline of description hash `key`, or the one `make` creates (with its
/// layout), counted for [`GpuContext::take_pipeline_counts`].
fn cached(
    ctx: &Arc<GpuContext>,
    key: u64,
    make: impl FnOnce() -> GpuResult<(vk::Pipeline, PipelineLayout)>,
) -> GpuResult<Arc<SharedPipeline>> {
    let (shared, reused) = ctx.shared(key, || {
        let (raw, layout) = make()?;
        Ok(SharedPipeline { ctx: ctx.clone(), raw, layout })
    })?;
    ctx.count_pipeline(reused);
    Ok(shared)
}

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

destroy_on_drop!(
    PipelineLayout => destroy_pipeline_layout,
    SharedPipeline => destroy_pipeline,
);

/// Vertex input of a graphics pipeline.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum VertexLayout {
    /// No vertex buffers (full-screen triangle, points generated from gl_VertexIndex).
    None,
    /// `crate::shader_structs::Vertex`: position vec3, normal vec3, checker uv vec2 (32 bytes).
    Mesh,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Blend {
    Off,
    Additive,
}

#[derive(Clone, Copy, Debug, Hash)]
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
    /// Specialisation constants of both stages, by name.
    pub specialization: Specs<'a>,
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
    pub(crate) raw: vk::Pipeline,
    pub(crate) layout: vk::PipelineLayout,
    _shared: Arc<SharedPipeline>,
}

fn shader_module(ctx: &GpuContext, path: &str, code: &ShaderCode) -> GpuResult<vk::ShaderModule> {
    let info = vk::ShaderModuleCreateInfo::default().code(&code.words);
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
        let (vs_code, fs_code) = (ctx.shader(desc.vertex_shader)?, ctx.shader(desc.fragment_shader)?);
        let shaders = [(desc.vertex_shader, &vs_code), (desc.fragment_shader, &fs_code)];
        let specialization = specialize(&shaders, desc.specialization)?;
        let state = (desc.vertex, desc.topology, desc.cull, desc.depth, desc.blend, &pass.desc);
        let key = pipeline_key(desc.name, &shaders, &specialization, sets, push_bytes, state);
        let shared = cached(ctx, key, || {
            let (data, entries) = &specialization;
            let layout = PipelineLayout::new(ctx, desc.name, sets, push_bytes)?;
            let vs = shader_module(ctx, desc.vertex_shader, &vs_code)?;
            let fs = shader_module(ctx, desc.fragment_shader, &fs_code)?;
            let spec: Vec<_> = entries
                .iter()
                .map(|e| vk::SpecializationInfo::default().map_entries(e).data(bytemuck::cast_slice(data)))
                .collect();
            let stages = [
                vk::PipelineShaderStageCreateInfo::default()
                    .stage(vk::ShaderStageFlags::VERTEX)
                    .module(vs)
                    .name(c"main")
                    .specialization_info(&spec[0]),
                vk::PipelineShaderStageCreateInfo::default()
                    .stage(vk::ShaderStageFlags::FRAGMENT)
                    .module(fs)
                    .name(c"main")
                    .specialization_info(&spec[1]),
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
            let blends: Vec<_> =
                desc.blend
                    .iter()
                    .map(|b| match b {
                        Blend::Off => vk::PipelineColorBlendAttachmentState::default()
                            .color_write_mask(vk::ColorComponentFlags::RGBA),
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
            Ok((raw, layout))
        })?;
        Ok(GraphicsPipeline { raw: shared.raw, layout: shared.layout.raw, _shared: shared })
    }
}

pub struct ComputePipeline {
    pub(crate) raw: vk::Pipeline,
    pub(crate) layout: vk::PipelineLayout,
    _shared: Arc<SharedPipeline>,
}

impl ComputePipeline {
    /// As [`GraphicsPipeline::new`]: a compute pipeline with a layout of its own.
    pub fn new(
        ctx: &Arc<GpuContext>,
        name: &str,
        shader: &str,
        sets: &[&DescriptorSetLayout],
        push_bytes: u32,
        specialization: Specs<'_>,
    ) -> GpuResult<Self> {
        let code = ctx.shader(shader)?;
        let specialization = specialize(&[(shader, &code)], specialization)?;
        let key = pipeline_key(name, &[(shader, &code)], &specialization, sets, push_bytes, "compute");
        let shared = cached(ctx, key, || {
            let (data, entries) = &specialization;
            let layout = PipelineLayout::new(ctx, name, sets, push_bytes)?;
            let module = shader_module(ctx, shader, &code)?;
            let spec = vk::SpecializationInfo::default().map_entries(&entries[0]).data(bytemuck::cast_slice(data));
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
            Ok((raw, layout))
        })?;
        Ok(ComputePipeline { raw: shared.raw, layout: shared.layout.raw, _shared: shared })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::gpu::SpecConstant;

    /// (name, SpecId) of every named specialisation constant in SPIR-V `words`.
    fn spirv_spec_ids(words: &[u32]) -> Vec<(String, u32)> {
        const OP_NAME: u32 = 5;
        const OP_DECORATE: u32 = 71;
        const SPEC_ID: u32 = 1;
        let (mut names, mut ids) = (std::collections::HashMap::new(), Vec::new());
        let mut at = 5;
        while at < words.len() {
            let (count, op) = ((words[at] >> 16) as usize, words[at] & 0xffff);
            let operands = &words[at + 1..at + count];
            if op == OP_NAME {
                let bytes: Vec<u8> = bytemuck::cast_slice(&operands[1..]).to_vec();
                let name = String::from_utf8_lossy(&bytes).trim_end_matches('\0').to_string();
                names.insert(operands[0], name);
            } else if op == OP_DECORATE && operands[1] == SPEC_ID {
                ids.push((operands[0], operands[2]));
            }
            at += count.max(1);
        }
        ids.into_iter().map(|(target, id)| (names[&target].clone(), id)).collect()
    }

    /// The declarations found in the sources name every constant the SPIR-V kept, with its id:
    /// pipelines can trust them for every shader.
    #[test]
    fn declared_constants_match_the_spirv() {
        let mut checked = 0;
        for path in crate::gpu::shader_names() {
            let code = crate::gpu::shader_code(path).unwrap();
            for (name, id) in spirv_spec_ids(&code.words) {
                let decl = code.specs.iter().find(|d| d.name == name);
                assert_eq!(decl.map(|d| d.id), Some(id), "{path}: {name}");
                checked += 1;
            }
        }
        assert!(checked > 60, "only {checked} specialisation constants found");
    }

    fn code(specs: &[(&str, u32, &str)]) -> ShaderCode {
        let specs = specs.iter().map(|&(n, id, ty)| SpecConstant { name: n.into(), id, ty: ty.into() }).collect();
        ShaderCode { words: Vec::new(), specs }
    }

    #[test]
    fn constants_are_found_by_name_in_each_stage() {
        let vs = code(&[("HAS_DN", 1, "uint")]);
        let fs = code(&[("MODE", 0, "uint"), ("TOLERANCE", 3, "float")]);
        let specs = [("TOLERANCE", Spec::F32(0.5)), ("HAS_DN", Spec::U32(1)), ("MODE", Spec::U32(2))];
        let (data, entries) = specialize(&[("a.vert", &vs), ("a.frag", &fs)], &specs).unwrap();
        assert_eq!(data, [0.5f32.to_bits(), 1, 2]);
        let ids = |e: &[vk::SpecializationMapEntry]| e.iter().map(|e| (e.constant_id, e.offset)).collect::<Vec<_>>();
        assert_eq!(ids(&entries[0]), [(1, 4)]);
        assert_eq!(ids(&entries[1]), [(3, 0), (0, 8)]);
    }

    #[test]
    fn unknown_or_mistyped_constants_name_the_shader() {
        let fs = code(&[("MODE", 0, "uint")]);
        let stages = [("x/y.frag", &fs)];
        let e = specialize(&stages, &[("MOED", Spec::U32(1))]).unwrap_err().to_string();
        assert!(e.contains("x/y.frag") && e.contains("MOED") && e.contains("declared: MODE"), "{e}");
        let e = specialize(&stages, &[("MODE", Spec::F32(1.0))]).unwrap_err().to_string();
        assert!(e.contains("x/y.frag") && e.contains("MODE") && e.contains("uint"), "{e}");
        let e = specialize(&stages, &[("MODE", Spec::U32(1)), ("MODE", Spec::U32(2))]).unwrap_err().to_string();
        assert!(e.contains("set twice"), "{e}");
    }
}
