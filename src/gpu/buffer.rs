//! Buffers with gpu-allocator memory, freed after the last frame that used them.
use std::sync::Arc;

use ash::vk;
use gpu_allocator::vulkan::Allocation;
use gpu_allocator::MemoryLocation;

use super::context::{Garbage, GpuContext, MemoryKind};
use super::error::{GpuError, GpuResult, VkContext};

pub struct Buffer {
    ctx: Arc<GpuContext>,
    pub(crate) raw: vk::Buffer,
    allocation: Option<Allocation>,
    pub size: u64,
    pub name: String,
}

impl Buffer {
    pub fn new(
        ctx: &Arc<GpuContext>,
        name: &str,
        size: u64,
        usage: vk::BufferUsageFlags,
        location: MemoryLocation,
    ) -> GpuResult<Buffer> {
        let size = size.max(4);
        let info = vk::BufferCreateInfo::default().size(size).usage(usage).sharing_mode(vk::SharingMode::EXCLUSIVE);
        let device = ctx.raw();
        // SAFETY: valid create info.
        let raw = unsafe { device.create_buffer(&info, None) }.vk("vkCreateBuffer")?;
        // SAFETY: raw is a fresh buffer.
        let requirements = unsafe { device.get_buffer_memory_requirements(raw) };
        let allocation = ctx.allocate(name, requirements, location, true).inspect_err(|_| {
            // SAFETY: unbound, unused buffer.
            unsafe { device.destroy_buffer(raw, None) }
        })?;
        // SAFETY: memory comes from a compatible type with the required size/alignment.
        unsafe { device.bind_buffer_memory(raw, allocation.memory(), allocation.offset()) }.vk("vkBindBufferMemory")?;
        ctx.set_name(raw, name);
        ctx.track(MemoryKind::Buffer, allocation.size(), true);
        Ok(Buffer { ctx: ctx.clone(), raw, allocation: Some(allocation), size, name: name.into() })
    }

    /// A host-visible buffer filled with `data`.
    pub fn with_data<T: bytemuck::Pod>(
        ctx: &Arc<GpuContext>,
        name: &str,
        data: &[T],
        usage: vk::BufferUsageFlags,
    ) -> GpuResult<Buffer> {
        let bytes: &[u8] = bytemuck::cast_slice(data);
        let mut b = Buffer::new(ctx, name, bytes.len() as u64, usage, MemoryLocation::CpuToGpu)?;
        b.write(0, bytes);
        Ok(b)
    }

    /// A host-visible buffer of `data` read only as texels of `format` (at least one texel
    /// long: a view cannot be empty), and that view.
    pub fn texels<T: bytemuck::Pod>(
        ctx: &Arc<GpuContext>,
        name: &str,
        data: &[T],
        format: vk::Format,
    ) -> GpuResult<(Buffer, BufferView)> {
        let bytes: &[u8] = bytemuck::cast_slice(data);
        let size = (bytes.len() as u64).max(texel_bytes(format)?);
        let usage = vk::BufferUsageFlags::UNIFORM_TEXEL_BUFFER;
        let mut buffer = Buffer::new(ctx, name, size, usage, MemoryLocation::CpuToGpu)?;
        buffer.write(0, bytes);
        let view = BufferView::new(ctx, &buffer, format)?;
        Ok((buffer, view))
    }

    /// A host-visible storage buffer filled with `data`.
    pub fn storage<T: bytemuck::Pod>(ctx: &Arc<GpuContext>, name: &str, data: &[T]) -> GpuResult<Buffer> {
        Buffer::with_data(ctx, name, data, vk::BufferUsageFlags::STORAGE_BUFFER)
    }

    /// Copy `data` into a host-visible buffer at byte `offset`.
    pub fn write(&mut self, offset: usize, data: &[u8]) {
        let slice = self
            .allocation
            .as_mut()
            .and_then(|a| a.mapped_slice_mut())
            .expect("Buffer::write needs a host-visible buffer");
        slice[offset..offset + data.len()].copy_from_slice(data);
    }

    /// The contents of a host-visible buffer.
    pub fn read(&self) -> &[u8] {
        self.allocation
            .as_ref()
            .and_then(|a| a.mapped_slice())
            .map(|s| &s[..self.size as usize])
            .expect("Buffer::read needs a host-visible buffer")
    }

    pub fn raw(&self) -> vk::Buffer {
        self.raw
    }
}

/// A buffer read through a formatted view (`texelFetch` on a `samplerBuffer` in GLSL). On
/// lavapipe a texel fetch at a per-lane index is one gather, where a storage-buffer load is a
/// loop over the SIMD lanes with a branch per lane and component (gallivm's `emit_load_mem`).
pub struct BufferView {
    ctx: Arc<GpuContext>,
    pub(crate) raw: vk::BufferView,
}

/// The size of one texel of the formats prism reads buffers as.
fn texel_bytes(format: vk::Format) -> GpuResult<u64> {
    match format {
        vk::Format::R32_UINT => Ok(4),
        vk::Format::R32G32B32A32_UINT | vk::Format::R32G32B32A32_SFLOAT => Ok(16),
        _ => Err(GpuError::Unsupported(format!("texel buffers of {format:?}"))),
    }
}

impl BufferView {
    /// `buffer` (made with `UNIFORM_TEXEL_BUFFER` usage) whole, as texels of `format`. Refused
    /// with the device's limit named when the buffer holds more texels than
    /// `maxTexelBufferElements` (at least 65 536; lavapipe 2^27).
    pub fn new(ctx: &Arc<GpuContext>, buffer: &Buffer, format: vk::Format) -> GpuResult<BufferView> {
        let texel_bytes = texel_bytes(format)?;
        let texels = buffer.size / texel_bytes;
        let max = u64::from(ctx.limits().max_texel_buffer_elements);
        if texels > max {
            return Err(GpuError::Unsupported(format!(
                "{} holds {texels} texels; the device's maxTexelBufferElements is {max}: use a smaller scene \
                 (fewer triangles or vertices) or another device",
                buffer.name
            )));
        }
        let info =
            vk::BufferViewCreateInfo::default().buffer(buffer.raw).format(format).offset(0).range(texels * texel_bytes);
        // SAFETY: valid create info; the buffer outlives the view's uses (both are freed
        // after the last frame that used them).
        let raw = unsafe { ctx.raw().create_buffer_view(&info, None) }.vk("vkCreateBufferView")?;
        ctx.set_name(raw, &buffer.name);
        Ok(BufferView { ctx: ctx.clone(), raw })
    }
}

impl Drop for BufferView {
    fn drop(&mut self) {
        self.ctx.defer_destroy(Garbage::BufferView(self.raw));
    }
}

impl Drop for Buffer {
    fn drop(&mut self) {
        if let Some(a) = self.allocation.take() {
            self.ctx.track(MemoryKind::Buffer, a.size(), false);
            self.ctx.defer_destroy(Garbage::Buffer(self.raw, a));
        }
    }
}
