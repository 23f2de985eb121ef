//! A small linear frame graph (../shared/DESIGN.md, rule 3).
//!
//! Passes run in the order they are added. Each declares the resources it reads and writes
//! with an [`Access`]; a per-resource "last access" table, kept across frames, turns each
//! pair of accesses into the barrier and layout transition Vulkan needs. Passes therefore
//! never record a barrier themselves. Every pass is wrapped in the same debug label and
//! pair of timestamps, under one snake_case name (rule 5).
use std::collections::HashSet;
use std::sync::{Arc, Weak};

use crate::gpu::{
    read_aspect, texel_layout, vk, Access, Buffer, BufferBarrier, Cmd, GpuContext, GpuResult, Image, ImageBarrier,
    ImageDesc, MemoryLocation, PipelineStatsPool, TimestampPool, TimestampQuery,
};

#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct ImageId(usize);

#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct BufferId(usize);

/// A resource the graph tracks: what a [`Bindings`] entry names for its barriers.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Res {
    Image(usize),
    Buffer(usize),
}

impl From<ImageId> for Res {
    fn from(id: ImageId) -> Res {
        Res::Image(id.0)
    }
}

impl From<BufferId> for Res {
    fn from(id: BufferId) -> Res {
        Res::Buffer(id.0)
    }
}

/// A descriptor set declared once, its resources tracked by this graph
/// ([`crate::gpu::Bindings`]).
pub type Bindings<'a> = crate::gpu::Bindings<'a, Res>;
/// A built [`Bindings`]: a pass declares all its accesses with [`PassBuilder::uses`].
pub type BoundSet = crate::gpu::BoundSet<Res>;

/// What the graph remembers about a resource between passes and between frames.
#[derive(Clone, Copy, Debug)]
struct State {
    layout: vk::ImageLayout,
    /// Stages and access of the last write (or layout transition), if any since creation.
    last_write: Option<(vk::PipelineStageFlags, vk::AccessFlags)>,
    /// Stages to which the last write has already been made visible.
    visible: vk::PipelineStageFlags,
    /// Stages that read the resource since the last write (for write-after-read).
    reads: vk::PipelineStageFlags,
}

impl State {
    const NEW: State = State {
        layout: vk::ImageLayout::UNDEFINED,
        last_write: None,
        visible: vk::PipelineStageFlags::empty(),
        reads: vk::PipelineStageFlags::empty(),
    };
}

struct ImageSlot {
    raw: vk::Image,
    aspect: vk::ImageAspectFlags,
    layers: u32,
    depth: bool,
    name: String,
    state: State,
    /// Format and extent (width, height, 3D depth), for read-back.
    format: vk::Format,
    extent: [u32; 3],
    /// The image's [`Image::liveness`]; `None` for an external image, which the graph never
    /// reads back.
    alive: Option<Weak<()>>,
}

/// An image the graph tracks and can read back ([`FrameGraph::images`]).
#[derive(Clone, Debug)]
pub struct TrackedImage {
    pub id: ImageId,
    pub name: String,
    pub format: vk::Format,
    pub width: u32,
    pub height: u32,
    /// Slices of a 3D image; 1 otherwise.
    pub depth: u32,
    pub layers: u32,
    /// Something wrote it or gave it a layout: its contents are defined.
    pub written: bool,
}

struct BufferSlot {
    raw: vk::Buffer,
    name: String,
    state: State,
}

/// The resources known to the graph and their last access. Lives as long as the renderer.
#[derive(Default)]
pub struct FrameGraph {
    images: Vec<ImageSlot>,
    buffers: Vec<BufferSlot>,
    skip_barriers: HashSet<Res>,
}

/// The src/dst half of a barrier computed for one access.
struct Transition {
    src_stages: vk::PipelineStageFlags,
    src_access: vk::AccessFlags,
    dst_stages: vk::PipelineStageFlags,
    dst_access: vk::AccessFlags,
    old_layout: vk::ImageLayout,
    new_layout: vk::ImageLayout,
}

/// Update `state` for `access` and return the barrier needed before it, if any.
fn transition(state: &mut State, access: Access, depth: bool, is_image: bool) -> Option<Transition> {
    let info = access.info(depth);
    let new_layout = if is_image { info.layout } else { vk::ImageLayout::UNDEFINED };
    let layout_change = is_image && state.layout != new_layout;
    let (w_stages, w_access) = state.last_write.unwrap_or((vk::PipelineStageFlags::empty(), vk::AccessFlags::empty()));

    if info.writes || layout_change {
        // Write-after-write, write-after-read, or a layout transition: wait for every earlier
        // write and read, and make the last write available.
        let src = w_stages | state.reads;
        let t = Transition {
            src_stages: if src.is_empty() { vk::PipelineStageFlags::TOP_OF_PIPE } else { src },
            src_access: w_access,
            dst_stages: info.stages,
            dst_access: info.access,
            old_layout: state.layout,
            new_layout,
        };
        if info.writes {
            state.last_write = Some((info.stages, info.access));
            state.visible = vk::PipelineStageFlags::empty();
            state.reads = vk::PipelineStageFlags::empty();
        } else {
            // A layout transition acts as a write completed before `info.stages`: later
            // readers at other stages chain onto it with an execution dependency.
            state.last_write = Some((info.stages, vk::AccessFlags::empty()));
            state.visible = info.stages;
            state.reads = info.stages;
        }
        state.layout = new_layout;
        Some(t)
    } else {
        // Read-after-write: only if this stage has not yet seen the last write.
        let needed = state.last_write.is_some() && !state.visible.contains(info.stages);
        state.reads |= info.stages;
        if needed {
            state.visible |= info.stages;
            Some(Transition {
                src_stages: w_stages,
                src_access: w_access,
                dst_stages: info.stages,
                dst_access: info.access,
                old_layout: state.layout,
                new_layout: state.layout,
            })
        } else {
            None
        }
    }
}

impl FrameGraph {
    pub fn new() -> Self {
        Self::default()
    }

    pub fn register_image(&mut self, image: &Image) -> ImageId {
        let depth = image.aspect().contains(vk::ImageAspectFlags::DEPTH);
        self.images.push(ImageSlot {
            raw: image.raw,
            aspect: image.aspect(),
            layers: image.layers(),
            depth,
            name: image.name().to_string(),
            state: State::NEW,
            format: image.format(),
            extent: [image.desc.width, image.desc.height, image.depth()],
            alive: Some(image.liveness()),
        });
        ImageId(self.images.len() - 1)
    }

    /// Track an image the graph does not own through an [`Image`] (a swapchain image): its
    /// raw handle, aspect, layer count and a name for diagnostics.
    pub fn register_external_image(
        &mut self,
        raw: vk::Image,
        aspect: vk::ImageAspectFlags,
        layers: u32,
        name: &str,
    ) -> ImageId {
        self.images.push(ImageSlot {
            raw,
            aspect,
            layers,
            depth: aspect.contains(vk::ImageAspectFlags::DEPTH),
            name: name.to_string(),
            state: State::NEW,
            format: vk::Format::UNDEFINED,
            extent: [0, 0, 0],
            alive: None,
        });
        ImageId(self.images.len() - 1)
    }

    /// An external image's contents became undefined and the image usable from `stage` on:
    /// a swapchain image after vkAcquireNextImageKHR, whose semaphore the submission waits
    /// for at `stage`. The next access then transitions from UNDEFINED and its barrier
    /// starts at `stage`, which chains it after the semaphore wait.
    pub fn reacquire_image(&mut self, id: ImageId, stage: vk::PipelineStageFlags) {
        self.images[id.0].state = State {
            layout: vk::ImageLayout::UNDEFINED,
            last_write: Some((stage, vk::AccessFlags::empty())),
            visible: vk::PipelineStageFlags::empty(),
            reads: vk::PipelineStageFlags::empty(),
        };
    }

    /// A new image, registered.
    pub fn image(&mut self, ctx: &Arc<GpuContext>, desc: &ImageDesc) -> GpuResult<(Image, ImageId)> {
        let image = Image::new(ctx, desc)?;
        let id = self.register_image(&image);
        Ok((image, id))
    }

    pub fn register_buffer(&mut self, buffer: &Buffer) -> BufferId {
        self.buffers.push(BufferSlot { raw: buffer.raw, name: buffer.name.clone(), state: State::NEW });
        BufferId(self.buffers.len() - 1)
    }

    /// The layout an image is in after the passes recorded so far.
    pub fn image_layout(&self, id: ImageId) -> vk::ImageLayout {
        self.images[id.0].state.layout
    }

    pub fn image_name(&self, id: ImageId) -> &str {
        &self.images[id.0].name
    }

    pub fn buffer_name(&self, id: BufferId) -> &str {
        &self.buffers[id.0].name
    }

    /// Test-only fault injection: record no barrier for this resource (the state table is
    /// still updated). Lets a test prove that synchronization validation catches a missing
    /// barrier, so that "zero validation errors" in the other tests means something.
    #[doc(hidden)]
    pub fn skip_barriers_for_tests(&mut self, id: ImageId) {
        self.skip_barriers.insert(Res::Image(id.0));
    }

    #[doc(hidden)]
    pub fn skip_buffer_barriers_for_tests(&mut self, id: BufferId) {
        self.skip_barriers.insert(Res::Buffer(id.0));
    }

    /// Start a frame's pass list.
    pub fn frame(&mut self) -> Frame<'_, '_> {
        Frame { graph: self, passes: Vec::new(), release: Vec::new() }
    }

    /// Record the barriers for `uses` into `cmd` (used by the executor and by readback).
    fn apply(&mut self, cmd: &Cmd, uses: &[(Res, Access)]) {
        let mut images = Vec::new();
        let mut buffers = Vec::new();
        for &(res, access) in uses {
            let skip = self.skip_barriers.contains(&res);
            match res {
                Res::Image(i) => {
                    let slot = &mut self.images[i];
                    if let Some(t) = transition(&mut slot.state, access, slot.depth, true) {
                        if !skip {
                            images.push(ImageBarrier {
                                image: slot.raw,
                                aspect: slot.aspect,
                                layers: slot.layers,
                                src_stages: t.src_stages,
                                src_access: t.src_access,
                                dst_stages: t.dst_stages,
                                dst_access: t.dst_access,
                                old_layout: t.old_layout,
                                new_layout: t.new_layout,
                            });
                        }
                    }
                }
                Res::Buffer(i) => {
                    let slot = &mut self.buffers[i];
                    if let Some(t) = transition(&mut slot.state, access, false, false) {
                        if !skip {
                            buffers.push(BufferBarrier {
                                buffer: slot.raw,
                                src_stages: t.src_stages,
                                src_access: t.src_access,
                                dst_stages: t.dst_stages,
                                dst_access: t.dst_access,
                            });
                        }
                    }
                }
            }
        }
        cmd.barriers(&images, &buffers);
    }

    /// Declare accesses outside any pass (uploads, readbacks) and record their barriers now.
    pub fn access_now(&mut self, cmd: &Cmd, images: &[(ImageId, Access)], buffers: &[(BufferId, Access)]) {
        let uses: Vec<_> = images
            .iter()
            .map(|&(id, a)| (Res::Image(id.0), a))
            .chain(buffers.iter().map(|&(id, a)| (Res::Buffer(id.0), a)))
            .collect();
        self.apply(cmd, &uses);
    }

    /// Copy every layer (or slice) of `image` into host memory: one submission that waits for
    /// the GPU, then leaves the image in `after` (the access the next frame's passes expect;
    /// `Access::TransferRead` when nothing needs it back). `bytes_per_texel` is the format's
    /// size (16 for RGBA32F). For tests, reports and readbacks, never inside a frame.
    pub fn read_back(
        &mut self,
        ctx: &Arc<GpuContext>,
        image: &Image,
        id: ImageId,
        bytes_per_texel: u64,
        after: Access,
    ) -> GpuResult<Vec<u8>> {
        let texels = image.desc.width as u64 * image.desc.height as u64 * image.depth() as u64 * image.layers() as u64;
        self.copy_to_host(ctx, image.name(), texels * bytes_per_texel, id, after, |cmd, buffer| {
            cmd.copy_image_to_buffer(image, buffer)
        })
    }

    /// Write `bytes` to the start of the device-local `buffer` (registered as `id`) through a
    /// host-visible staging buffer: one submission that waits for the GPU, ordered after the
    /// buffer's last use. For uploads between frames (a light simulation's initial patches),
    /// never inside a frame.
    pub fn upload_buffer(
        &mut self,
        ctx: &Arc<GpuContext>,
        buffer: &Buffer,
        id: BufferId,
        bytes: &[u8],
    ) -> GpuResult<()> {
        if bytes.is_empty() {
            return Ok(());
        }
        let usage = vk::BufferUsageFlags::TRANSFER_SRC;
        let mut staging = Buffer::new(ctx, "upload_staging", bytes.len() as u64, usage, MemoryLocation::CpuToGpu)?;
        // Host-coherent, written before the submission: visible to the copy.
        staging.write(0, bytes);
        ctx.one_shot(|cmd| {
            self.access_now(cmd, &[], &[(id, Access::TransferWrite)]);
            cmd.copy_buffer(&staging, buffer, bytes.len() as u64);
        })
    }

    /// The first `bytes` of `buffer` (registered as `id`, device-local) in host memory,
    /// through a staging buffer: one submission that waits for the GPU. For tests and
    /// readbacks between frames, never inside a frame.
    pub fn read_back_buffer(
        &mut self,
        ctx: &Arc<GpuContext>,
        buffer: &Buffer,
        id: BufferId,
        bytes: u64,
    ) -> GpuResult<Vec<u8>> {
        if bytes == 0 {
            return Ok(Vec::new());
        }
        let usage = vk::BufferUsageFlags::TRANSFER_DST;
        let staging = Buffer::new(ctx, "readback_staging", bytes, usage, MemoryLocation::GpuToCpu)?;
        let staging_id = self.register_buffer(&staging);
        ctx.one_shot(|cmd| {
            self.access_now(cmd, &[], &[(id, Access::TransferRead), (staging_id, Access::TransferWrite)]);
            cmd.copy_buffer(buffer, &staging, bytes);
            self.access_now(cmd, &[], &[(staging_id, Access::HostRead)]);
        })?;
        Ok(staging.read()[..bytes as usize].to_vec())
    }

    /// Image `id` copied by `copy` into a host-visible buffer of `bytes`, between the barriers
    /// that make the copy see the image and the host see the copy; the image is left in
    /// `after`'s layout. One submission that waits for the GPU.
    fn copy_to_host(
        &mut self,
        ctx: &Arc<GpuContext>,
        name: &str,
        bytes: u64,
        id: ImageId,
        after: Access,
        copy: impl FnOnce(&crate::gpu::Cmd, &Buffer),
    ) -> GpuResult<Vec<u8>> {
        let usage = vk::BufferUsageFlags::TRANSFER_DST;
        let buffer = Buffer::new(ctx, &format!("{name}_readback"), bytes, usage, MemoryLocation::GpuToCpu)?;
        let buffer_id = self.register_buffer(&buffer);
        ctx.one_shot(|cmd| {
            self.access_now(cmd, &[(id, Access::TransferRead)], &[(buffer_id, Access::TransferWrite)]);
            copy(cmd, &buffer);
            self.access_now(cmd, &[(id, after)], &[(buffer_id, Access::HostRead)]);
        })?;
        Ok(buffer.read().to_vec())
    }
}

impl FrameGraph {
    /// Every image registered through an [`Image`] that still exists, in registration
    /// order; an image registered twice is listed once, under its last registration (whose
    /// state the passes update).
    pub fn images(&self) -> Vec<TrackedImage> {
        let live = |s: &ImageSlot| s.alive.as_ref().is_some_and(|w| w.strong_count() > 0);
        self.images
            .iter()
            .enumerate()
            .filter(|&(i, s)| live(s) && !self.images[i + 1..].iter().any(|t| t.raw == s.raw && live(t)))
            .map(|(i, s)| TrackedImage {
                id: ImageId(i),
                name: s.name.clone(),
                format: s.format,
                width: s.extent[0],
                height: s.extent[1],
                depth: s.extent[2],
                layers: s.layers,
                written: s.state.layout != vk::ImageLayout::UNDEFINED,
            })
            .collect()
    }

    /// Every texel of a tracked image, tightly packed (layer by layer, slice by slice, rows
    /// from the top), in its format's [`texel_layout`]; depth/stencil images give their depth
    /// aspect. One submission that waits for the GPU; the image is then returned to the
    /// layout it was in, so that whatever binds it without declaring an access (an atlas in
    /// the frame set) still finds it there. `None`: the image no longer exists, was never
    /// written (undefined contents), or has a format [`texel_layout`] does not know.
    pub fn read_back_image(&mut self, ctx: &Arc<GpuContext>, id: ImageId) -> GpuResult<Option<Vec<u8>>> {
        let slot = &self.images[id.0];
        let alive = slot.alive.as_ref().is_some_and(|w| w.strong_count() > 0);
        let Some((_, bytes_per_texel)) = texel_layout(slot.format) else { return Ok(None) };
        let Some(after) = access_in_layout(slot.state.layout, slot.depth) else { return Ok(None) };
        if !alive {
            return Ok(None);
        }
        let (raw, format, extent, layers) = (slot.raw, slot.format, slot.extent, slot.layers);
        let texels = extent.iter().map(|&e| e as u64).product::<u64>() * layers as u64;
        let name = slot.name.clone();
        let bytes = self.copy_to_host(ctx, &name, texels * bytes_per_texel as u64, id, after, |cmd, buffer| {
            cmd.copy_tracked_image_to_buffer(raw, read_aspect(format), extent, layers, buffer)
        })?;
        Ok(Some(bytes))
    }
}

/// An access that puts an image back in `layout` (what it was in before a read-back);
/// `None` for UNDEFINED, whose contents a read-back cannot show.
fn access_in_layout(layout: vk::ImageLayout, depth: bool) -> Option<Access> {
    use vk::ImageLayout as L;
    let candidates = [
        Access::FragmentSampled,
        Access::ColorAttachment,
        Access::DepthAttachment,
        Access::ComputeRead,
        Access::TransferRead,
        Access::TransferWrite,
        Access::Present,
    ];
    if layout == L::UNDEFINED {
        return None;
    }
    candidates.into_iter().find(|a| a.info(depth).layout == layout)
}

type RecordFn<'a> = Box<dyn FnOnce(&Cmd) + 'a>;

struct PassNode<'a> {
    name: String,
    uses: Vec<(Res, Access)>,
    record: RecordFn<'a>,
}

/// One frame's list of passes, executed in order.
pub struct Frame<'g, 'a> {
    graph: &'g mut FrameGraph,
    passes: Vec<PassNode<'a>>,
    /// Accesses after the last pass (see [`Frame::release`]).
    release: Vec<(Res, Access)>,
}

/// Builder for one pass: declare its accesses, then give the recording closure.
pub struct PassBuilder<'f, 'g, 'a> {
    frame: &'f mut Frame<'g, 'a>,
    name: String,
    uses: Vec<(Res, Access)>,
}

impl<'g, 'a> Frame<'g, 'a> {
    /// Add a pass named `name` (snake_case: it is also the timing and golden-image name).
    pub fn pass(&mut self, name: &str) -> PassBuilder<'_, 'g, 'a> {
        PassBuilder { frame: self, name: name.to_string(), uses: Vec::new() }
    }

    /// Declare an access that follows every pass of the frame, outside the command buffer:
    /// `Access::Present` for a swapchain image. Its barrier is recorded after the last pass.
    pub fn release(&mut self, id: ImageId, access: Access) {
        self.release.push((Res::Image(id.0), access));
    }

    pub fn pass_names(&self) -> Vec<&str> {
        self.passes.iter().map(|p| p.name.as_str()).collect()
    }

    /// Passes declared so far.
    pub fn pass_count(&self) -> usize {
        self.passes.len()
    }

    /// Names of the passes declared from index `first` on.
    pub fn pass_names_since(&self, first: usize) -> impl Iterator<Item = &str> + Clone {
        self.passes[first..].iter().map(|p| p.name.as_str())
    }

    /// Whether a pass declared from index `first` on reads or writes one of `images`.
    pub fn uses_any_since(&self, first: usize, images: &[ImageId]) -> bool {
        self.passes[first..]
            .iter()
            .flat_map(|p| &p.uses)
            .any(|(r, _)| matches!(r, Res::Image(i) if images.iter().any(|id| id.0 == *i)))
    }

    /// Record every pass into `cmd`: barriers, label, timestamps, the pass's commands.
    /// Returns the timestamp query pairs written (if a pool is given).
    pub fn execute(self, cmd: &Cmd, timestamps: Option<&TimestampPool>) -> Vec<TimestampQuery> {
        self.execute_with(cmd, timestamps, None)
    }

    /// [`Frame::execute`], also counting each pass's pipeline statistics into query `pass`
    /// of `stats` (the query of pass i is i; passes beyond its capacity are not counted).
    pub fn execute_with(
        self,
        cmd: &Cmd,
        timestamps: Option<&TimestampPool>,
        stats: Option<&PipelineStatsPool>,
    ) -> Vec<TimestampQuery> {
        let Frame { graph, passes, release } = self;
        let mut queries = Vec::new();
        if let Some(pool) = timestamps {
            cmd.reset_queries(pool);
        }
        if let Some(pool) = stats {
            cmd.reset_pipeline_stats(pool);
        }
        for (i, pass) in passes.into_iter().enumerate() {
            graph.apply(cmd, &pass.uses);
            cmd.begin_label(&pass.name);
            let q = timestamps.filter(|p| 2 * i as u32 + 1 < p.capacity());
            let s = stats.filter(|p| (i as u32) < p.capacity());
            if let Some(pool) = q {
                cmd.write_timestamp(pool, 2 * i as u32, vk::PipelineStageFlags::TOP_OF_PIPE);
            }
            if let Some(pool) = s {
                cmd.begin_pipeline_stats(pool, i as u32);
            }
            let work = cmd.work_recorded();
            (pass.record)(cmd);
            let ran = cmd.work_recorded() > work;
            if let Some(pool) = s {
                cmd.end_pipeline_stats(pool, i as u32);
            }
            if let Some(pool) = q {
                cmd.write_timestamp(pool, 2 * i as u32 + 1, vk::PipelineStageFlags::BOTTOM_OF_PIPE);
                queries.push(TimestampQuery {
                    name: pass.name.clone(),
                    pass: i as u32,
                    start: 2 * i as u32,
                    end: 2 * i as u32 + 1,
                    ran,
                });
            }
            cmd.end_label();
        }
        graph.apply(cmd, &release);
        queries
    }
}

impl<'f, 'g, 'a> PassBuilder<'f, 'g, 'a> {
    /// The pass reads the image or buffer `id` as `access`.
    pub fn read(self, id: impl Into<Res>, access: Access) -> Self {
        self.access(id.into(), access)
    }
    /// The pass writes the image or buffer `id` as `access`.
    pub fn write(self, id: impl Into<Res>, access: Access) -> Self {
        self.access(id.into(), access)
    }
    // Reads and writes differ only in name: the access says what the barriers wait for.
    fn access(mut self, res: Res, access: Access) -> Self {
        self.uses.push((res, access));
        self
    }
    /// Every access of the resources `set` binds.
    pub fn uses(mut self, set: &BoundSet) -> Self {
        self.uses.extend_from_slice(set.uses());
        self
    }
    /// Finish the pass with the closure that records its commands.
    pub fn record(self, f: impl FnOnce(&Cmd) + 'a) {
        self.frame.passes.push(PassNode { name: self.name, uses: self.uses, record: Box::new(f) });
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn write_then_read_needs_one_barrier_per_new_stage() {
        let mut s = State::NEW;
        let t = transition(&mut s, Access::ColorAttachment, false, true).unwrap();
        assert_eq!(t.old_layout, vk::ImageLayout::UNDEFINED);
        assert_eq!(t.new_layout, vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL);
        let t = transition(&mut s, Access::FragmentSampled, false, true).unwrap();
        assert_eq!(t.src_stages, vk::PipelineStageFlags::COLOR_ATTACHMENT_OUTPUT);
        assert_eq!(t.src_access, vk::AccessFlags::COLOR_ATTACHMENT_READ | vk::AccessFlags::COLOR_ATTACHMENT_WRITE);
        assert_eq!(t.new_layout, vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL);
        // Same stage again: nothing to do.
        assert!(transition(&mut s, Access::FragmentSampled, false, true).is_none());
        // A vertex-shader read (caustic splatting) has not seen the write's transition yet.
        let t = transition(&mut s, Access::VertexSampled, false, true).unwrap();
        assert_eq!(t.dst_stages, vk::PipelineStageFlags::VERTEX_SHADER);
        // Writing again must wait for both readers (write-after-read).
        let t = transition(&mut s, Access::ColorAttachment, false, true).unwrap();
        assert!(t.src_stages.contains(vk::PipelineStageFlags::FRAGMENT_SHADER | vk::PipelineStageFlags::VERTEX_SHADER));
    }

    #[test]
    fn buffers_have_no_layouts_and_storage_writes_serialise() {
        let mut s = State::NEW;
        let t = transition(&mut s, Access::ComputeWrite, false, false).unwrap();
        assert_eq!(t.new_layout, vk::ImageLayout::UNDEFINED);
        let t = transition(&mut s, Access::ComputeWrite, false, false).unwrap();
        assert_eq!(t.src_access, vk::AccessFlags::SHADER_READ | vk::AccessFlags::SHADER_WRITE);
        let t = transition(&mut s, Access::IndirectArgs, false, false).unwrap();
        assert_eq!(t.dst_stages, vk::PipelineStageFlags::DRAW_INDIRECT);
    }

    #[test]
    fn reacquired_swapchain_image_waits_for_the_acquire_stage_and_ends_in_present() {
        let mut g = FrameGraph::new();
        let id = g.register_external_image(vk::Image::null(), vk::ImageAspectFlags::COLOR, 1, "swapchain_0");
        g.reacquire_image(id, vk::PipelineStageFlags::TRANSFER);
        let s = &mut g.images[id.0].state;
        let t = transition(s, Access::TransferWrite, false, true).unwrap();
        assert_eq!(t.src_stages, vk::PipelineStageFlags::TRANSFER);
        assert_eq!(t.old_layout, vk::ImageLayout::UNDEFINED);
        transition(s, Access::ColorAttachment, false, true).unwrap();
        let t = transition(s, Access::Present, false, true).unwrap();
        assert_eq!(t.src_stages, vk::PipelineStageFlags::COLOR_ATTACHMENT_OUTPUT);
        assert_eq!(t.new_layout, vk::ImageLayout::PRESENT_SRC_KHR);
        // Next frame: acquired again, contents undefined.
        g.reacquire_image(id, vk::PipelineStageFlags::TRANSFER);
        assert_eq!(g.image_layout(id), vk::ImageLayout::UNDEFINED);
    }

    #[test]
    fn depth_sampling_uses_the_read_only_depth_layout() {
        let mut s = State::NEW;
        transition(&mut s, Access::DepthAttachment, true, true);
        let t = transition(&mut s, Access::FragmentSampled, true, true).unwrap();
        assert_eq!(t.new_layout, vk::ImageLayout::DEPTH_STENCIL_READ_ONLY_OPTIMAL);
    }
}
