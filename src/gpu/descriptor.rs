//! Descriptor set layouts, each with a small pool of its own for the sets allocated from it.
use std::sync::Arc;

use ash::vk;

use super::context::GpuContext;
use super::error::{GpuResult, VkContext};
use super::{Buffer, Sampler};

pub struct DescriptorSetLayout {
    ctx: Arc<GpuContext>,
    pub(crate) raw: vk::DescriptorSetLayout,
    pool: vk::DescriptorPool,
    /// What it was made from: a pipeline's cache key (src/gpu/pipeline.rs).
    pub(super) bindings: Vec<Binding>,
}

/// One binding: (binding, type, stages). Arrays are not needed: lavapipe has no descriptor
/// indexing, and prism binds a fixed set of resources per pass.
pub(super) type Binding = (u32, vk::DescriptorType, vk::ShaderStageFlags);

impl DescriptorSetLayout {
    /// A layout with `bindings` and room for `max_sets` sets.
    pub(super) fn new(ctx: &Arc<GpuContext>, name: &str, bindings: &[Binding], max_sets: u32) -> GpuResult<Self> {
        let raw_bindings: Vec<_> = bindings
            .iter()
            .map(|&(b, ty, stages)| {
                vk::DescriptorSetLayoutBinding::default()
                    .binding(b)
                    .descriptor_type(ty)
                    .descriptor_count(1)
                    .stage_flags(stages)
            })
            .collect();
        let info = vk::DescriptorSetLayoutCreateInfo::default().bindings(&raw_bindings);
        let device = ctx.raw();
        // SAFETY: valid create info.
        let raw = unsafe { device.create_descriptor_set_layout(&info, None) }.vk("vkCreateDescriptorSetLayout")?;
        ctx.set_name(raw, name);
        let mut sizes: Vec<vk::DescriptorPoolSize> = Vec::new();
        for &(_, ty, _) in bindings {
            match sizes.iter_mut().find(|s| s.ty == ty) {
                Some(s) => s.descriptor_count += max_sets,
                None => sizes.push(vk::DescriptorPoolSize { ty, descriptor_count: max_sets }),
            }
        }
        let pool_info = vk::DescriptorPoolCreateInfo::default().max_sets(max_sets.max(1)).pool_sizes(&sizes);
        // SAFETY: valid create info.
        let pool = unsafe { device.create_descriptor_pool(&pool_info, None) }.vk("vkCreateDescriptorPool")?;
        ctx.set_name(pool, name);
        Ok(DescriptorSetLayout { ctx: ctx.clone(), raw, pool, bindings: bindings.to_vec() })
    }

    /// Allocate a set and fill it with `writes`.
    pub(super) fn allocate(&self, name: &str, writes: &[DescriptorWrite<'_>]) -> GpuResult<DescriptorSet> {
        let layouts = [self.raw];
        let info = vk::DescriptorSetAllocateInfo::default().descriptor_pool(self.pool).set_layouts(&layouts);
        // SAFETY: pool has room (sized by max_sets).
        let raw = unsafe { self.ctx.raw().allocate_descriptor_sets(&info) }.vk("vkAllocateDescriptorSets")?[0];
        self.ctx.set_name(raw, name);
        let set = DescriptorSet { raw };
        set.update(&self.ctx, writes);
        Ok(set)
    }
}

impl Drop for DescriptorSetLayout {
    fn drop(&mut self) {
        // SAFETY: dropped with the renderer after the device is idle; sets die with the pool.
        unsafe {
            self.ctx.raw().destroy_descriptor_pool(self.pool, None);
            self.ctx.raw().destroy_descriptor_set_layout(self.raw, None);
        }
    }
}

/// A descriptor set; freed with the pool of the layout it came from.
#[derive(Clone, Copy, Debug)]
pub struct DescriptorSet {
    pub(crate) raw: vk::DescriptorSet,
}

#[derive(Clone, Copy)]
pub(super) enum DescriptorWrite<'a> {
    Uniform(u32, &'a Buffer),
    Storage(u32, &'a Buffer),
    /// binding, view, sampler, layout the image will be in when sampled.
    Sampled(u32, vk::ImageView, &'a Sampler, vk::ImageLayout),
    StorageImage(u32, vk::ImageView),
    UniformTexels(u32, vk::BufferView),
}

impl DescriptorWrite<'_> {
    pub(super) fn binding(&self) -> u32 {
        match *self {
            DescriptorWrite::Uniform(b, _)
            | DescriptorWrite::Storage(b, _)
            | DescriptorWrite::Sampled(b, ..)
            | DescriptorWrite::StorageImage(b, _)
            | DescriptorWrite::UniformTexels(b, _) => b,
        }
    }

    pub(super) fn ty(&self) -> vk::DescriptorType {
        match self {
            DescriptorWrite::Uniform(..) => vk::DescriptorType::UNIFORM_BUFFER,
            DescriptorWrite::Storage(..) => vk::DescriptorType::STORAGE_BUFFER,
            DescriptorWrite::Sampled(..) => vk::DescriptorType::COMBINED_IMAGE_SAMPLER,
            DescriptorWrite::StorageImage(..) => vk::DescriptorType::STORAGE_IMAGE,
            DescriptorWrite::UniformTexels(..) => vk::DescriptorType::UNIFORM_TEXEL_BUFFER,
        }
    }
}

impl DescriptorSet {
    pub(super) fn update(&self, ctx: &GpuContext, writes: &[DescriptorWrite<'_>]) {
        let mut buffer_infos = Vec::with_capacity(writes.len());
        let mut image_infos = Vec::with_capacity(writes.len());
        let mut texel_views = Vec::with_capacity(writes.len());
        for w in writes {
            match w {
                DescriptorWrite::Uniform(_, b) | DescriptorWrite::Storage(_, b) => {
                    buffer_infos.push([vk::DescriptorBufferInfo { buffer: b.raw, offset: 0, range: vk::WHOLE_SIZE }])
                }
                DescriptorWrite::Sampled(_, view, sampler, layout) => image_infos.push([vk::DescriptorImageInfo {
                    sampler: sampler.raw,
                    image_view: *view,
                    image_layout: *layout,
                }]),
                DescriptorWrite::StorageImage(_, view) => image_infos.push([vk::DescriptorImageInfo {
                    sampler: vk::Sampler::null(),
                    image_view: *view,
                    image_layout: vk::ImageLayout::GENERAL,
                }]),
                DescriptorWrite::UniformTexels(_, view) => texel_views.push([*view]),
            }
        }
        let (mut bi, mut ii, mut ti) = (0, 0, 0);
        let raw_writes: Vec<_> = writes
            .iter()
            .map(|w| {
                let base = vk::WriteDescriptorSet::default()
                    .dst_set(self.raw)
                    .dst_binding(w.binding())
                    .descriptor_type(w.ty());
                match w {
                    DescriptorWrite::Uniform(..) | DescriptorWrite::Storage(..) => {
                        bi += 1;
                        base.buffer_info(&buffer_infos[bi - 1])
                    }
                    DescriptorWrite::Sampled(..) | DescriptorWrite::StorageImage(..) => {
                        ii += 1;
                        base.image_info(&image_infos[ii - 1])
                    }
                    DescriptorWrite::UniformTexels(..) => {
                        ti += 1;
                        base.texel_buffer_view(&texel_views[ti - 1])
                    }
                }
            })
            .collect();
        // SAFETY: every info array outlives the call; the set is not in use by a pending submission
        // (sets are written once, at creation, or after wait_idle on resize).
        unsafe { ctx.raw().update_descriptor_sets(&raw_writes, &[]) };
    }
}
