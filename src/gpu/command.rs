//! Command recording. [`Cmd`] is the only way passes touch a command buffer.
use std::ffi::CString;
use std::sync::Arc;

use ash::vk;

use super::context::{timeout_nanos, GpuContext, FRAME_TIMEOUT};
use super::error::{GpuResult, VkContext};
use super::sync::{Access, BufferBarrier, ImageBarrier};
use super::{
    Buffer, ComputePipeline, DescriptorSet, Framebuffer, GraphicsPipeline, Image, OcclusionQueryPool,
    PipelineStatsPool, RenderPass, RenderTarget, TimestampPool,
};

/// A tightly packed copy of every layer of `image` to or from a buffer.
fn whole_image_region(image: &Image) -> vk::BufferImageCopy {
    vk::BufferImageCopy {
        buffer_offset: 0,
        buffer_row_length: 0,
        buffer_image_height: 0,
        image_subresource: vk::ImageSubresourceLayers {
            aspect_mask: image.aspect(),
            mip_level: 0,
            base_array_layer: 0,
            layer_count: image.layers(),
        },
        image_offset: vk::Offset3D::default(),
        image_extent: vk::Extent3D { width: image.desc.width, height: image.desc.height, depth: image.depth() },
    }
}

/// A command buffer in the recording state.
pub struct Cmd<'a> {
    ctx: &'a GpuContext,
    pub(crate) raw: vk::CommandBuffer,
    /// Commands that do work on the device (draws, dispatches, copies, clears, render-pass
    /// begins) recorded so far: the frame graph tells a pass that recorded nothing this
    /// frame (a cached map not due) from one that ran, by comparing it before and after.
    work: std::cell::Cell<u64>,
}

/// What a render pass attachment is cleared to.
#[derive(Clone, Copy, Debug)]
pub enum Clear {
    Color([f32; 4]),
    Depth(f32),
    /// Attachment is loaded, the value is unused.
    None,
}

impl<'a> Cmd<'a> {
    pub(crate) fn wrap(ctx: &'a GpuContext, raw: vk::CommandBuffer) -> Self {
        Cmd { ctx, raw, work: std::cell::Cell::new(0) }
    }

    /// Device work recorded so far (see the field's doc): only differences mean anything.
    pub fn work_recorded(&self) -> u64 {
        self.work.get()
    }

    fn note_work(&self) {
        self.work.set(self.work.get() + 1);
    }

    fn dev(&self) -> &ash::Device {
        self.ctx.raw()
    }

    /// Order the accesses `from` of `buffer` before the accesses `to`, for a buffer the
    /// frame graph does not track.
    pub fn buffer_barrier(&self, buffer: &Buffer, from: Access, to: Access) {
        let (from, to) = (from.info(false), to.info(false));
        self.barriers(
            &[],
            &[BufferBarrier {
                buffer: buffer.raw,
                src_stages: from.stages,
                src_access: from.access,
                dst_stages: to.stages,
                dst_access: to.access,
            }],
        );
    }

    pub fn barriers(&self, images: &[ImageBarrier], buffers: &[BufferBarrier]) {
        if images.is_empty() && buffers.is_empty() {
            return;
        }
        let mut src = vk::PipelineStageFlags::empty();
        let mut dst = vk::PipelineStageFlags::empty();
        let image_barriers: Vec<_> = images
            .iter()
            .map(|b| {
                src |= b.src_stages;
                dst |= b.dst_stages;
                vk::ImageMemoryBarrier::default()
                    .src_access_mask(b.src_access)
                    .dst_access_mask(b.dst_access)
                    .old_layout(b.old_layout)
                    .new_layout(b.new_layout)
                    .src_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
                    .dst_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
                    .image(b.image)
                    .subresource_range(vk::ImageSubresourceRange {
                        aspect_mask: b.aspect,
                        base_mip_level: 0,
                        level_count: 1,
                        base_array_layer: 0,
                        layer_count: b.layers,
                    })
            })
            .collect();
        let buffer_barriers: Vec<_> = buffers
            .iter()
            .map(|b| {
                src |= b.src_stages;
                dst |= b.dst_stages;
                vk::BufferMemoryBarrier::default()
                    .src_access_mask(b.src_access)
                    .dst_access_mask(b.dst_access)
                    .src_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
                    .dst_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
                    .buffer(b.buffer)
                    .offset(0)
                    .size(vk::WHOLE_SIZE)
            })
            .collect();
        // SAFETY: recording command buffer; barrier structs are valid for the call.
        unsafe {
            self.dev().cmd_pipeline_barrier(
                self.raw,
                src,
                dst,
                vk::DependencyFlags::empty(),
                &[],
                &buffer_barriers,
                &image_barriers,
            )
        };
    }

    /// Open a debug-utils label (RenderDoc and the validation layer show it).
    pub fn begin_label(&self, name: &str) {
        if let Some(du) = &self.ctx.debug_utils_device {
            let name = CString::new(name).unwrap_or_default();
            let label = vk::DebugUtilsLabelEXT::default().label_name(&name);
            // SAFETY: recording command buffer.
            unsafe { du.cmd_begin_debug_utils_label(self.raw, &label) };
        }
    }

    pub fn end_label(&self) {
        if let Some(du) = &self.ctx.debug_utils_device {
            // SAFETY: paired with begin_label.
            unsafe { du.cmd_end_debug_utils_label(self.raw) };
        }
    }

    /// Begin `pass` on `fb` and set the viewport and scissor to the framebuffer.
    /// Record `draw` inside `pass` on `fb`: the pass begins before and ends after it, so a
    /// begin is never left without its end.
    /// [`Self::in_render_pass`] into framebuffer `framebuffer` of `target`.
    pub fn in_target<R>(
        &self,
        target: &RenderTarget,
        framebuffer: usize,
        clears: &[Clear],
        draw: impl FnOnce(&Cmd) -> R,
    ) -> R {
        self.in_render_pass(&target.pass, &target.framebuffers()[framebuffer], clears, draw)
    }

    pub fn in_render_pass<R>(
        &self,
        pass: &RenderPass,
        fb: &Framebuffer,
        clears: &[Clear],
        draw: impl FnOnce(&Cmd) -> R,
    ) -> R {
        self.begin_render_pass(pass, fb, clears);
        let r = draw(self);
        self.end_render_pass();
        r
    }

    fn begin_render_pass(&self, pass: &RenderPass, fb: &Framebuffer, clears: &[Clear]) {
        let values: Vec<vk::ClearValue> = clears
            .iter()
            .map(|c| match *c {
                Clear::Color(v) => vk::ClearValue { color: vk::ClearColorValue { float32: v } },
                Clear::Depth(d) => {
                    vk::ClearValue { depth_stencil: vk::ClearDepthStencilValue { depth: d, stencil: 0 } }
                }
                Clear::None => vk::ClearValue::default(),
            })
            .collect();
        let info = vk::RenderPassBeginInfo::default()
            .render_pass(pass.raw)
            .framebuffer(fb.raw)
            .render_area(vk::Rect2D { offset: vk::Offset2D::default(), extent: fb.extent })
            .clear_values(&values);
        self.note_work();
        // SAFETY: recording, outside any render pass.
        unsafe { self.dev().cmd_begin_render_pass(self.raw, &info, vk::SubpassContents::INLINE) };
        self.set_viewport(fb.extent);
    }

    pub fn set_viewport(&self, extent: vk::Extent2D) {
        let viewport = vk::Viewport {
            x: 0.0,
            y: 0.0,
            width: extent.width as f32,
            height: extent.height as f32,
            min_depth: 0.0,
            max_depth: 1.0,
        };
        let scissor = vk::Rect2D { offset: vk::Offset2D::default(), extent };
        // SAFETY: recording; dynamic state declared by every graphics pipeline.
        unsafe {
            self.dev().cmd_set_viewport(self.raw, 0, &[viewport]);
            self.dev().cmd_set_scissor(self.raw, 0, &[scissor]);
        }
    }

    /// Limit the following draws to `rect` (inside a render pass; [`Cmd::set_viewport`]
    /// resets it to the whole target).
    pub fn set_scissor(&self, rect: vk::Rect2D) {
        // SAFETY: recording; dynamic state declared by every graphics pipeline.
        unsafe { self.dev().cmd_set_scissor(self.raw, 0, &[rect]) };
    }

    fn end_render_pass(&self) {
        // SAFETY: inside a render pass begun by begin_render_pass.
        unsafe { self.dev().cmd_end_render_pass(self.raw) };
    }

    pub fn bind_graphics(&self, p: &GraphicsPipeline, sets: &[DescriptorSet]) {
        // SAFETY: recording; sets are compatible with the pipeline's layout.
        unsafe {
            self.dev().cmd_bind_pipeline(self.raw, vk::PipelineBindPoint::GRAPHICS, p.raw);
            if !sets.is_empty() {
                let raw: Vec<_> = sets.iter().map(|s| s.raw).collect();
                self.dev().cmd_bind_descriptor_sets(self.raw, vk::PipelineBindPoint::GRAPHICS, p.layout, 0, &raw, &[]);
            }
        }
    }

    pub fn bind_compute(&self, p: &ComputePipeline, sets: &[DescriptorSet]) {
        // SAFETY: as bind_graphics.
        unsafe {
            self.dev().cmd_bind_pipeline(self.raw, vk::PipelineBindPoint::COMPUTE, p.raw);
            if !sets.is_empty() {
                let raw: Vec<_> = sets.iter().map(|s| s.raw).collect();
                self.dev().cmd_bind_descriptor_sets(self.raw, vk::PipelineBindPoint::COMPUTE, p.layout, 0, &raw, &[]);
            }
        }
    }

    /// Push constants for the graphics pipeline `p` (all stages).
    pub fn push_graphics<T: bytemuck::Pod>(&self, p: &GraphicsPipeline, value: &T) {
        // SAFETY: the layout declares a range for all stages at offset 0 of at least this size.
        unsafe {
            self.dev().cmd_push_constants(self.raw, p.layout, vk::ShaderStageFlags::ALL, 0, bytemuck::bytes_of(value))
        };
    }

    pub fn push_compute<T: bytemuck::Pod>(&self, p: &ComputePipeline, value: &T) {
        // SAFETY: as push_graphics.
        unsafe {
            self.dev().cmd_push_constants(self.raw, p.layout, vk::ShaderStageFlags::ALL, 0, bytemuck::bytes_of(value))
        };
    }

    pub fn bind_mesh_buffers(&self, vertices: &Buffer, indices: &Buffer) {
        // SAFETY: recording; buffers were created with VERTEX/INDEX usage.
        unsafe {
            self.dev().cmd_bind_vertex_buffers(self.raw, 0, &[vertices.raw], &[0]);
            self.dev().cmd_bind_index_buffer(self.raw, indices.raw, 0, vk::IndexType::UINT32);
        }
    }

    /// Bind `vertices` alone, for non-indexed draws.
    pub fn bind_vertex_buffer(&self, vertices: &Buffer) {
        // SAFETY: recording; the buffer was created with VERTEX usage.
        unsafe { self.dev().cmd_bind_vertex_buffers(self.raw, 0, &[vertices.raw], &[0]) };
    }

    pub fn draw(&self, vertices: u32, instances: u32) {
        self.note_work();
        // SAFETY: recording inside a render pass with a bound graphics pipeline.
        unsafe { self.dev().cmd_draw(self.raw, vertices, instances, 0, 0) };
    }

    /// One draw whose vertex count and first vertex the GPU wrote: a VkDrawIndirectCommand
    /// at byte `offset` of `buffer`.
    pub fn draw_indirect(&self, buffer: &Buffer, offset: u64) {
        self.note_work();
        // SAFETY: recording inside a render pass with a bound graphics pipeline; the buffer
        // has INDIRECT_BUFFER usage and holds a VkDrawIndirectCommand at `offset`.
        unsafe { self.dev().cmd_draw_indirect(self.raw, buffer.raw, offset, 1, 0) };
    }

    pub fn draw_indexed(&self, index_count: u32, first_index: u32, vertex_offset: i32) {
        self.note_work();
        // SAFETY: as draw, with bound index/vertex buffers.
        unsafe { self.dev().cmd_draw_indexed(self.raw, index_count, 1, first_index, vertex_offset, 0) };
    }

    pub fn dispatch(&self, x: u32, y: u32, z: u32) {
        self.note_work();
        // SAFETY: recording outside a render pass with a bound compute pipeline.
        unsafe { self.dev().cmd_dispatch(self.raw, x, y, z) };
    }

    /// A compute dispatch whose group counts (three u32) are read by the device from
    /// `buffer` at byte `offset`: GPU-generated work sizes without a CPU round trip (the
    /// HistoPyramid's output count, src/technique/eikonal/histopyramid.rs).
    pub fn dispatch_indirect(&self, buffer: &Buffer, offset: u64) {
        self.note_work();
        // SAFETY: recording outside a render pass with a bound compute pipeline; the buffer
        // has INDIRECT_BUFFER usage and holds a VkDispatchIndirectCommand at `offset`.
        unsafe { self.dev().cmd_dispatch_indirect(self.raw, buffer.raw, offset) };
    }

    /// Bind `p` and `sets`, push `push` and dispatch `groups` workgroups: the commands of
    /// most compute passes.
    pub fn compute<T: bytemuck::Pod>(&self, p: &ComputePipeline, sets: &[DescriptorSet], push: &T, groups: [u32; 3]) {
        self.bind_compute(p, sets);
        self.push_compute(p, push);
        self.dispatch(groups[0], groups[1], groups[2]);
    }

    /// As [`Cmd::compute`], with the group counts read from `buffer` at byte `offset`
    /// ([`Cmd::dispatch_indirect`]).
    pub fn compute_indirect<T: bytemuck::Pod>(
        &self,
        p: &ComputePipeline,
        sets: &[DescriptorSet],
        push: &T,
        buffer: &Buffer,
        offset: u64,
    ) {
        self.bind_compute(p, sets);
        self.push_compute(p, push);
        self.dispatch_indirect(buffer, offset);
    }

    pub fn write_timestamp(&self, pool: &TimestampPool, query: u32, stage: vk::PipelineStageFlags) {
        // SAFETY: query < pool size; the pool was reset this frame.
        unsafe { self.dev().cmd_write_timestamp(self.raw, stage, pool.raw, query) };
        if pool.clock_on_flush {
            // An empty execution dependency orders nothing, but lavapipe flushes on every
            // barrier, which reads the clock for the timestamp just written.
            // SAFETY: recording outside a render pass (the graph times whole passes).
            unsafe {
                self.dev().cmd_pipeline_barrier(
                    self.raw,
                    vk::PipelineStageFlags::TOP_OF_PIPE,
                    vk::PipelineStageFlags::BOTTOM_OF_PIPE,
                    vk::DependencyFlags::empty(),
                    &[],
                    &[],
                    &[],
                )
            };
        }
    }

    pub fn reset_queries(&self, pool: &TimestampPool) {
        // SAFETY: recording outside a render pass.
        unsafe { self.dev().cmd_reset_query_pool(self.raw, pool.raw, 0, pool.capacity) };
    }

    /// Reset every query of a pipeline-statistics pool (outside a render pass).
    pub fn reset_pipeline_stats(&self, pool: &PipelineStatsPool) {
        // SAFETY: recording outside a render pass.
        unsafe { self.dev().cmd_reset_query_pool(self.raw, pool.raw, 0, pool.capacity) };
    }

    /// Start counting pass `query`'s pipeline statistics. Begun and ended outside any render
    /// pass (the frame graph wraps whole passes), so a pass's render passes lie inside it.
    pub fn begin_pipeline_stats(&self, pool: &PipelineStatsPool, query: u32) {
        assert!(query < pool.capacity, "pipeline-statistics query {query} of {}", pool.capacity);
        // SAFETY: query < capacity, reset earlier in this command buffer; no other query of
        // this type is active (the graph ends each pass's query before the next begins).
        unsafe { self.dev().cmd_begin_query(self.raw, pool.raw, query, vk::QueryControlFlags::empty()) };
    }

    pub fn end_pipeline_stats(&self, pool: &PipelineStatsPool, query: u32) {
        // SAFETY: the query was begun by begin_pipeline_stats in this command buffer.
        unsafe { self.dev().cmd_end_query(self.raw, pool.raw, query) };
    }

    /// Reset every query of `pool` (outside a render pass, before the queries begin).
    pub fn reset_occlusion_queries(&self, pool: &OcclusionQueryPool) {
        // SAFETY: recording outside a render pass.
        unsafe { self.dev().cmd_reset_query_pool(self.raw, pool.raw, 0, pool.capacity) };
    }

    pub fn begin_occlusion_query(&self, pool: &OcclusionQueryPool, query: u32) {
        assert!(query < pool.capacity, "occlusion query {query} of {}", pool.capacity);
        // SAFETY: query < capacity, reset earlier in this command buffer; PRECISE only when
        // the feature is enabled (OcclusionQueryPool::new).
        unsafe { self.dev().cmd_begin_query(self.raw, pool.raw, query, pool.flags) };
    }

    pub fn end_occlusion_query(&self, pool: &OcclusionQueryPool, query: u32) {
        // SAFETY: matches a begin_occlusion_query in the same render pass instance.
        unsafe { self.dev().cmd_end_query(self.raw, pool.raw, query) };
    }

    /// Copy every query's sample count of `pool` into `buffer` as u32s, waiting on the GPU
    /// (WAIT flag) for each to be available: a transfer write to `buffer`, outside a render
    /// pass, after the queries ended.
    pub fn copy_occlusion_results(&self, pool: &OcclusionQueryPool, buffer: &Buffer) {
        // SAFETY: buffer holds capacity u32s and has TRANSFER_DST usage (caller); outside a render pass.
        unsafe {
            self.dev().cmd_copy_query_pool_results(
                self.raw,
                pool.raw,
                0,
                pool.capacity,
                buffer.raw,
                0,
                4,
                vk::QueryResultFlags::WAIT,
            )
        };
    }

    /// Copy the first `bytes` of `src` to the start of `dst` (the caller ordered both).
    pub fn copy_buffer(&self, src: &Buffer, dst: &Buffer, bytes: u64) {
        if bytes == 0 {
            return;
        }
        self.note_work();
        let region = vk::BufferCopy { src_offset: 0, dst_offset: 0, size: bytes };
        // SAFETY: both buffers are at least `bytes` long (the callers size them), src has
        // TRANSFER_SRC and dst TRANSFER_DST usage, and the caller recorded the barriers.
        unsafe { self.dev().cmd_copy_buffer(self.raw, src.raw, dst.raw, &[region]) };
    }

    /// Copy every layer of `image` (in TRANSFER_SRC_OPTIMAL) tightly into `buffer`.
    pub fn copy_image_to_buffer(&self, image: &Image, buffer: &Buffer) {
        let region = whole_image_region(image);
        self.note_work();
        // SAFETY: the caller transitioned the image to TRANSFER_SRC_OPTIMAL; buffer is large enough.
        unsafe {
            self.dev().cmd_copy_image_to_buffer(
                self.raw,
                image.raw,
                vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
                buffer.raw,
                &[region],
            )
        };
    }

    /// Copy one `aspect` of every layer of a tracked image (in TRANSFER_SRC_OPTIMAL, of
    /// `extent` texels and `layers` layers) tightly into `buffer`: the frame graph's read-back
    /// of an image it knows by handle, not through an [`Image`].
    pub fn copy_tracked_image_to_buffer(
        &self,
        image: vk::Image,
        aspect: vk::ImageAspectFlags,
        extent: [u32; 3],
        layers: u32,
        buffer: &Buffer,
    ) {
        let region = vk::BufferImageCopy {
            buffer_offset: 0,
            buffer_row_length: 0,
            buffer_image_height: 0,
            image_subresource: vk::ImageSubresourceLayers {
                aspect_mask: aspect,
                mip_level: 0,
                base_array_layer: 0,
                layer_count: layers,
            },
            image_offset: vk::Offset3D::default(),
            image_extent: vk::Extent3D { width: extent[0], height: extent[1], depth: extent[2] },
        };
        self.note_work();
        // SAFETY: the caller transitioned the image to TRANSFER_SRC_OPTIMAL, the extent and
        // layers are the image's own, and the buffer holds every texel.
        unsafe {
            self.dev().cmd_copy_image_to_buffer(
                self.raw,
                image,
                vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
                buffer.raw,
                &[region],
            )
        };
    }

    /// Copy `buffer` into every layer of `image` (in TRANSFER_DST_OPTIMAL).
    pub fn copy_buffer_to_image(&self, buffer: &Buffer, image: &Image) {
        let region = whole_image_region(image);
        self.note_work();
        // SAFETY: the caller transitioned the image to TRANSFER_DST_OPTIMAL; buffer holds the texels.
        unsafe {
            self.dev().cmd_copy_buffer_to_image(
                self.raw,
                buffer.raw,
                image.raw,
                vk::ImageLayout::TRANSFER_DST_OPTIMAL,
                &[region],
            )
        };
    }

    /// Copy whole layers `layers` of `src` (in TRANSFER_SRC_OPTIMAL) to the same layers of `dst`
    /// (in TRANSFER_DST_OPTIMAL); both colour images of the same extent and format.
    pub fn copy_image_layers(&self, src: &Image, dst: &Image, layers: &[u32]) {
        let regions: Vec<vk::ImageCopy> = layers
            .iter()
            .map(|&layer| {
                let sub = vk::ImageSubresourceLayers {
                    aspect_mask: vk::ImageAspectFlags::COLOR,
                    mip_level: 0,
                    base_array_layer: layer,
                    layer_count: 1,
                };
                vk::ImageCopy {
                    src_subresource: sub,
                    src_offset: vk::Offset3D::default(),
                    dst_subresource: sub,
                    dst_offset: vk::Offset3D::default(),
                    extent: vk::Extent3D { width: src.desc.width, height: src.desc.height, depth: 1 },
                }
            })
            .collect();
        if regions.is_empty() {
            return;
        }
        self.note_work();
        // SAFETY: the caller transitioned both images (frame graph); the layers exist in both,
        // which were created alike with TRANSFER_SRC / TRANSFER_DST usage.
        unsafe {
            self.dev().cmd_copy_image(
                self.raw,
                src.raw,
                vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
                dst.raw,
                vk::ImageLayout::TRANSFER_DST_OPTIMAL,
                &regions,
            )
        };
    }

    /// Clear every layer of a colour image (in TRANSFER_DST_OPTIMAL).
    pub fn clear_color_image(&self, image: &Image, value: [f32; 4]) {
        let range = vk::ImageSubresourceRange {
            aspect_mask: vk::ImageAspectFlags::COLOR,
            base_mip_level: 0,
            level_count: 1,
            base_array_layer: 0,
            layer_count: image.layers(),
        };
        self.note_work();
        // SAFETY: the caller transitioned the image to TRANSFER_DST_OPTIMAL.
        unsafe {
            self.dev().cmd_clear_color_image(
                self.raw,
                image.raw,
                vk::ImageLayout::TRANSFER_DST_OPTIMAL,
                &vk::ClearColorValue { float32: value },
                &[range],
            )
        };
    }

    /// Blit all of `src` (in TRANSFER_SRC_OPTIMAL) onto all of the external image `dst` (in
    /// TRANSFER_DST_OPTIMAL, e.g. a swapchain image), scaling with `filter` and converting
    /// between colour formats (RGBA to BGRA).
    pub fn blit_to(&self, src: &Image, dst: vk::Image, dst_extent: vk::Extent2D, filter: vk::Filter) {
        let layers = vk::ImageSubresourceLayers {
            aspect_mask: vk::ImageAspectFlags::COLOR,
            mip_level: 0,
            base_array_layer: 0,
            layer_count: 1,
        };
        let corner = |w: u32, h: u32| vk::Offset3D { x: w as i32, y: h as i32, z: 1 };
        let region = vk::ImageBlit {
            src_subresource: layers,
            src_offsets: [vk::Offset3D::default(), corner(src.desc.width, src.desc.height)],
            dst_subresource: layers,
            dst_offsets: [vk::Offset3D::default(), corner(dst_extent.width, dst_extent.height)],
        };
        self.note_work();
        // SAFETY: the caller transitioned both images (frame graph); both are single-layer
        // colour images created with TRANSFER_SRC / TRANSFER_DST usage.
        unsafe {
            self.dev().cmd_blit_image(
                self.raw,
                src.raw,
                vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
                dst,
                vk::ImageLayout::TRANSFER_DST_OPTIMAL,
                &[region],
                filter,
            )
        };
    }

    /// Fill a buffer with a repeated u32 (clearing counters and accumulation buffers).
    pub fn fill_buffer(&self, buffer: &Buffer, value: u32) {
        self.note_work();
        // SAFETY: recording outside a render pass; buffer has TRANSFER_DST usage.
        unsafe { self.dev().cmd_fill_buffer(self.raw, buffer.raw, 0, vk::WHOLE_SIZE, value) };
    }
}

/// Semaphores a frame's submission waits for (each at a pipeline stage) and signals: the
/// swapchain's acquire and present semaphores. Empty for headless frames.
#[derive(Clone, Debug, Default)]
pub struct SubmitSync {
    pub wait: Vec<(vk::Semaphore, vk::PipelineStageFlags)>,
    pub signal: Vec<vk::Semaphore>,
}

/// Command buffers and fences for `frames` frames in flight.
pub struct CommandPool {
    ctx: Arc<GpuContext>,
    pool: vk::CommandPool,
    buffers: Vec<vk::CommandBuffer>,
    fences: Vec<vk::Fence>,
    /// Submission serial of each slot's last submit (0 = never submitted).
    serials: Vec<u64>,
}

impl CommandPool {
    pub fn new(ctx: &Arc<GpuContext>, frames: u32) -> GpuResult<CommandPool> {
        let device = ctx.raw();
        let info = vk::CommandPoolCreateInfo::default()
            .queue_family_index(ctx.queue_family)
            .flags(vk::CommandPoolCreateFlags::RESET_COMMAND_BUFFER);
        // SAFETY: valid create infos throughout.
        let pool = unsafe { device.create_command_pool(&info, None) }.vk("vkCreateCommandPool")?;
        ctx.set_name(pool, "frame_command_pool");
        let alloc = vk::CommandBufferAllocateInfo::default()
            .command_pool(pool)
            .level(vk::CommandBufferLevel::PRIMARY)
            .command_buffer_count(frames);
        // SAFETY: the pool was just created on this device.
        let buffers = unsafe { device.allocate_command_buffers(&alloc) }.vk("vkAllocateCommandBuffers")?;
        let mut fences = Vec::new();
        for i in 0..frames {
            // SAFETY: valid create info.
            let f = unsafe {
                device.create_fence(&vk::FenceCreateInfo::default().flags(vk::FenceCreateFlags::SIGNALED), None)
            }
            .vk("vkCreateFence")?;
            ctx.set_name(f, &format!("frame_fence_{i}"));
            ctx.set_name(buffers[i as usize], &format!("frame_cmd_{i}"));
            fences.push(f);
        }
        Ok(CommandPool { ctx: ctx.clone(), pool, buffers, fences, serials: vec![0; frames as usize] })
    }

    pub fn frames(&self) -> usize {
        self.buffers.len()
    }

    /// Wait for slot `i`'s previous submission (its results are then readable), without
    /// starting a new recording. Returns whether the slot had been submitted before.
    pub fn wait(&mut self, i: usize) -> GpuResult<bool> {
        self.ctx.wait_for_fence(self.fences[i], "a frame's command buffer", FRAME_TIMEOUT)?;
        let had = self.serials[i] != 0;
        if had {
            self.ctx.mark_completed(self.serials[i]);
        }
        Ok(had)
    }

    /// Wait for slot `i`, then begin recording into its command buffer.
    pub fn begin(&mut self, i: usize) -> GpuResult<Cmd<'_>> {
        self.wait(i)?;
        let device = self.ctx.raw();
        // SAFETY: the slot's previous submission has completed (fence waited above).
        unsafe {
            device.reset_fences(&[self.fences[i]]).vk("vkResetFences")?;
            device
                .reset_command_buffer(self.buffers[i], vk::CommandBufferResetFlags::empty())
                .vk("vkResetCommandBuffer")?;
            device
                .begin_command_buffer(
                    self.buffers[i],
                    &vk::CommandBufferBeginInfo::default().flags(vk::CommandBufferUsageFlags::ONE_TIME_SUBMIT),
                )
                .vk("vkBeginCommandBuffer")?;
        }
        Ok(Cmd::wrap(&self.ctx, self.buffers[i]))
    }

    /// End and submit slot `i`.
    pub fn submit(&mut self, i: usize) -> GpuResult<()> {
        self.submit_with(i, &SubmitSync::default())
    }

    /// End and submit slot `i`, waiting for and signalling the semaphores in `sync`.
    pub fn submit_with(&mut self, i: usize, sync: &SubmitSync) -> GpuResult<()> {
        // SAFETY: slot i is recording (begin was called).
        unsafe { self.ctx.raw().end_command_buffer(self.buffers[i]) }.vk("vkEndCommandBuffer")?;
        self.serials[i] = self.ctx.submit(self.buffers[i], self.fences[i], sync)?;
        Ok(())
    }
}

impl Drop for CommandPool {
    fn drop(&mut self) {
        // SAFETY: wait for every slot, then destroy; nothing else references these objects.
        // Past the timeout the work may still run (a stopped process, a slow device): wait
        // for the device rather than destroy objects in use.
        unsafe {
            if self.ctx.raw().wait_for_fences(&self.fences, true, timeout_nanos(FRAME_TIMEOUT)).is_err() {
                let _ = self.ctx.raw().device_wait_idle();
            }
            for &f in &self.fences {
                self.ctx.raw().destroy_fence(f, None);
            }
            self.ctx.raw().destroy_command_pool(self.pool, None);
        }
    }
}
