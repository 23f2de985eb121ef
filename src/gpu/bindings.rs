//! A descriptor set declared once: each resource with its binding number, its stages and,
//! where the frame graph tracks it, its graph handle and access. From that one list come
//! the set layout, the descriptor writes and the pass's declared accesses (kajiya's
//! `SimpleRenderPass::read(&h)` binds and declares a resource in one call; wgpu-hal derives
//! layout entries and writes from one `BindGroupLayoutEntry` list).
//!
//! The handle type `H` is the frame graph's (the gpu layer does not know it): the built set
//! keeps `(H, Access)` pairs that the graph turns into barriers when a pass uses the set.
use std::sync::Arc;

use ash::vk;

use super::context::GpuContext;
use super::error::{GpuError, GpuResult};
use super::{Access, Buffer, BufferView, DescriptorSet, DescriptorSetLayout, DescriptorWrite, Image, Sampler};

/// The resources of one descriptor set, in binding order of declaration.
pub struct Bindings<'a, H> {
    stages: vk::ShaderStageFlags,
    entries: Vec<(DescriptorWrite<'a>, vk::ShaderStageFlags)>,
    uses: Vec<(H, Access)>,
}

/// The read access a stage set implies for a sampled image (`sampled`) or a storage buffer.
fn reads(stages: vk::ShaderStageFlags, sampled: bool) -> Vec<Access> {
    use vk::ShaderStageFlags as S;
    let mut v = Vec::new();
    if stages.contains(S::VERTEX) {
        v.push(if sampled { Access::VertexSampled } else { Access::VertexStorageRead });
    }
    if stages.contains(S::FRAGMENT) {
        v.push(if sampled { Access::FragmentSampled } else { Access::FragmentStorageRead });
    }
    if stages.contains(S::COMPUTE) {
        v.push(if sampled { Access::ComputeSampled } else { Access::ComputeRead });
    }
    v
}

/// The layout a sampled image is in when the graph gives it a sampled access.
fn sampled_layout(image: &Image) -> vk::ImageLayout {
    Access::FragmentSampled.info(image.aspect().contains(vk::ImageAspectFlags::DEPTH)).layout
}

impl<'a, H: Copy> Bindings<'a, H> {
    /// An empty set whose resources are visible to `stages` (until [`Self::stages`]).
    pub fn new(stages: vk::ShaderStageFlags) -> Self {
        Bindings { stages, entries: Vec::new(), uses: Vec::new() }
    }

    /// The stages of the resources declared from here on.
    pub fn stages(mut self, stages: vk::ShaderStageFlags) -> Self {
        self.stages = stages;
        self
    }

    fn push(mut self, write: DescriptorWrite<'a>) -> Self {
        self.entries.push((write, self.stages));
        self
    }

    pub fn uniform(self, binding: u32, buffer: &'a Buffer) -> Self {
        self.push(DescriptorWrite::Uniform(binding, buffer))
    }

    pub fn storage(self, binding: u32, buffer: &'a Buffer) -> Self {
        self.push(DescriptorWrite::Storage(binding, buffer))
    }

    /// A buffer read through `view` as a uniform texel buffer (`samplerBuffer` in GLSL).
    pub fn texels(self, binding: u32, view: &'a BufferView) -> Self {
        self.push(DescriptorWrite::UniformTexels(binding, view.raw))
    }

    /// `image` (its default view) sampled with `sampler`, in the layout of a sampled access.
    pub fn sampled(self, binding: u32, image: &'a Image, sampler: &'a Sampler) -> Self {
        self.sampled_view(binding, image, image.view(), sampler)
    }

    /// As [`Self::sampled`], through another view of `image` (a cube map as a 2D array).
    pub fn sampled_view(self, binding: u32, image: &'a Image, view: vk::ImageView, sampler: &'a Sampler) -> Self {
        let layout = sampled_layout(image);
        self.push(DescriptorWrite::Sampled(binding, view, sampler, layout))
    }

    /// `image` as a storage image (GENERAL layout).
    pub fn storage_image(self, binding: u32, image: &'a Image) -> Self {
        self.push(DescriptorWrite::StorageImage(binding, image.view()))
    }

    /// The graph tracks the resource declared last as `handle`, read at the set's stages.
    pub fn read(mut self, handle: impl Into<H>) -> Self {
        let (write, stages) = self.entries.last().expect("read() follows a resource");
        let sampled = matches!(write, DescriptorWrite::Sampled(..));
        let handle = handle.into();
        for access in reads(*stages, sampled) {
            self.uses.push((handle, access));
        }
        self
    }

    /// The graph tracks the resource declared last as `handle`, with `access` (writes).
    pub fn access(mut self, handle: impl Into<H>, access: Access) -> Self {
        self.uses.push((handle.into(), access));
        self
    }

    fn layout(&self, ctx: &Arc<GpuContext>, name: &str, max_sets: u32) -> GpuResult<DescriptorSetLayout> {
        let bindings: Vec<_> = self.entries.iter().map(|(w, stages)| (w.binding(), w.ty(), *stages)).collect();
        DescriptorSetLayout::new(ctx, name, &bindings, max_sets)
    }

    fn writes(&self) -> Vec<DescriptorWrite<'a>> {
        self.entries.iter().map(|(w, _)| *w).collect()
    }

    /// The layout, one set written with the resources, and their graph accesses.
    pub fn build(self, ctx: &Arc<GpuContext>, name: &str) -> GpuResult<BoundSet<H>> {
        let layout = self.layout(ctx, name, 1)?;
        let set = layout.allocate(name, &self.writes())?;
        Ok(BoundSet { layout, sets: vec![set], uses: self.uses })
    }

    /// One layout and a set per element of `sets` (same bindings, other resources): a pass
    /// drawing once per instance. The accesses are those of every set.
    pub fn build_each(ctx: &Arc<GpuContext>, name: &str, sets: Vec<Self>) -> GpuResult<BoundSet<H>> {
        let first = sets.first().ok_or_else(|| GpuError::Unsupported(format!("{name}: no descriptor set")))?;
        let layout = first.layout(ctx, name, sets.len() as u32)?;
        let shape = |b: &Self| b.entries.iter().map(|(w, s)| (w.binding(), w.ty(), *s)).collect::<Vec<_>>();
        let mut out = BoundSet { sets: Vec::new(), uses: Vec::new(), layout };
        let expected = shape(first);
        for b in sets {
            debug_assert!(shape(&b) == expected, "{name}: every set of one layout binds the same slots");
            out.sets.push(out.layout.allocate(name, &b.writes())?);
            out.uses.extend(b.uses);
        }
        Ok(out)
    }
}

/// A built descriptor set layout, its set(s), and the graph accesses of what they bind.
pub struct BoundSet<H> {
    layout: DescriptorSetLayout,
    sets: Vec<DescriptorSet>,
    uses: Vec<(H, Access)>,
}

impl<H: Copy> BoundSet<H> {
    pub fn layout(&self) -> &DescriptorSetLayout {
        &self.layout
    }

    /// The (first) set.
    pub fn set(&self) -> DescriptorSet {
        self.sets[0]
    }

    /// Every set, in the order of [`Bindings::build_each`].
    pub fn sets(&self) -> &[DescriptorSet] {
        &self.sets
    }

    /// The graph accesses of the bound resources.
    pub fn uses(&self) -> &[(H, Access)] {
        &self.uses
    }

    /// Write the resources `b` declares into every set again, with no set in use by the
    /// device: the frame sets when an atlas they bind is replaced. The layout stays, so the
    /// pipelines made with it stay valid.
    pub fn rewrite(&self, ctx: &GpuContext, b: Bindings<'_, H>) {
        let writes = b.writes();
        for set in &self.sets {
            set.update(ctx, &writes);
        }
    }
}
