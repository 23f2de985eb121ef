//! Images, their views, and samplers.
use std::sync::Arc;

use ash::vk;
use gpu_allocator::vulkan::Allocation;
use gpu_allocator::MemoryLocation;

use super::context::{Garbage, GpuContext, MemoryKind};
use super::error::{GpuResult, VkContext};

/// How the default view of an image is typed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ImageViewKind {
    D2,
    D2Array,
    Cube,
    CubeArray,
    /// A 3D image of `depth` slices (volume textures); `layers` stays 1.
    D3 {
        depth: u32,
    },
}

#[derive(Clone, Debug)]
pub struct ImageDesc {
    pub name: String,
    pub format: vk::Format,
    pub width: u32,
    pub height: u32,
    pub layers: u32,
    pub usage: vk::ImageUsageFlags,
    pub view: ImageViewKind,
}

impl ImageDesc {
    /// A 3D image (volume texture) of `width` x `height` x `depth` texels.
    pub fn d3(name: &str, format: vk::Format, extent: [u32; 3], usage: vk::ImageUsageFlags) -> Self {
        let [width, height, depth] = extent;
        ImageDesc { name: name.into(), format, width, height, layers: 1, usage, view: ImageViewKind::D3 { depth } }
    }

    /// Texels along z: the depth of a 3D image, 1 otherwise.
    pub fn depth(&self) -> u32 {
        match self.view {
            ImageViewKind::D3 { depth } => depth.max(1),
            _ => 1,
        }
    }

    /// A square image of `size`^2 texels and `layers` layers.
    pub fn square(
        name: &str,
        format: vk::Format,
        size: u32,
        layers: u32,
        view: ImageViewKind,
        usage: vk::ImageUsageFlags,
    ) -> Self {
        ImageDesc { name: name.into(), format, width: size, height: size, layers, usage, view }
    }

    pub fn d2(name: &str, format: vk::Format, width: u32, height: u32, usage: vk::ImageUsageFlags) -> Self {
        ImageDesc { name: name.into(), format, width, height, layers: 1, usage, view: ImageViewKind::D2 }
    }
}

pub struct Image {
    ctx: Arc<GpuContext>,
    pub(crate) raw: vk::Image,
    /// The view over all layers, typed by `desc.view`.
    pub(crate) view: vk::ImageView,
    /// One 2D view per layer, for rendering into a single cube face or array layer.
    pub(crate) layer_views: Vec<vk::ImageView>,
    /// A 2D-array view over all layers (for sampling a cube-compatible image as layers).
    pub(crate) array_view: Option<vk::ImageView>,
    allocation: Option<Allocation>,
    pub desc: ImageDesc,
}

pub(crate) fn aspect_of(format: vk::Format) -> vk::ImageAspectFlags {
    match format {
        vk::Format::D16_UNORM | vk::Format::D32_SFLOAT | vk::Format::X8_D24_UNORM_PACK32 => vk::ImageAspectFlags::DEPTH,
        vk::Format::D24_UNORM_S8_UINT | vk::Format::D32_SFLOAT_S8_UINT => {
            vk::ImageAspectFlags::DEPTH | vk::ImageAspectFlags::STENCIL
        }
        _ => vk::ImageAspectFlags::COLOR,
    }
}

/// Volumes (3D images) apart from the other images in [`super::MemoryKinds`].
fn memory_kind(desc: &ImageDesc) -> MemoryKind {
    if matches!(desc.view, ImageViewKind::D3 { .. }) {
        MemoryKind::Volume
    } else {
        MemoryKind::Image
    }
}

impl Image {
    pub fn new(ctx: &Arc<GpuContext>, desc: &ImageDesc) -> GpuResult<Image> {
        let device = ctx.raw();
        let cube = matches!(desc.view, ImageViewKind::Cube | ImageViewKind::CubeArray);
        let d3 = matches!(desc.view, ImageViewKind::D3 { .. });
        let info = vk::ImageCreateInfo::default()
            .image_type(if d3 { vk::ImageType::TYPE_3D } else { vk::ImageType::TYPE_2D })
            .format(desc.format)
            .extent(vk::Extent3D { width: desc.width.max(1), height: desc.height.max(1), depth: desc.depth() })
            .mip_levels(1)
            .array_layers(desc.layers.max(1))
            .samples(vk::SampleCountFlags::TYPE_1)
            .tiling(vk::ImageTiling::OPTIMAL)
            .usage(desc.usage)
            .flags(if cube { vk::ImageCreateFlags::CUBE_COMPATIBLE } else { vk::ImageCreateFlags::empty() })
            .initial_layout(vk::ImageLayout::UNDEFINED);
        // SAFETY: valid create info.
        let raw = unsafe { device.create_image(&info, None) }.vk("vkCreateImage")?;
        // SAFETY: fresh image.
        let requirements = unsafe { device.get_image_memory_requirements(raw) };
        let allocation = ctx.allocate(&desc.name, requirements, MemoryLocation::GpuOnly, false).inspect_err(|_| {
            // SAFETY: unbound, unused image.
            unsafe { device.destroy_image(raw, None) }
        })?;
        // SAFETY: compatible memory.
        unsafe { device.bind_image_memory(raw, allocation.memory(), allocation.offset()) }.vk("vkBindImageMemory")?;
        ctx.set_name(raw, &desc.name);
        ctx.track(memory_kind(desc), allocation.size(), true);

        let aspect = aspect_of(desc.format);
        let make_view = |ty: vk::ImageViewType, base: u32, count: u32| {
            let info =
                vk::ImageViewCreateInfo::default().image(raw).view_type(ty).format(desc.format).subresource_range(
                    vk::ImageSubresourceRange {
                        aspect_mask: aspect,
                        base_mip_level: 0,
                        level_count: 1,
                        base_array_layer: base,
                        layer_count: count,
                    },
                );
            // SAFETY: view within the image's subresources.
            unsafe { device.create_image_view(&info, None) }.vk("vkCreateImageView")
        };
        let layers = desc.layers.max(1);
        let view_type = match desc.view {
            ImageViewKind::D2 => vk::ImageViewType::TYPE_2D,
            ImageViewKind::D2Array => vk::ImageViewType::TYPE_2D_ARRAY,
            ImageViewKind::Cube => vk::ImageViewType::CUBE,
            ImageViewKind::CubeArray => vk::ImageViewType::CUBE_ARRAY,
            ImageViewKind::D3 { .. } => vk::ImageViewType::TYPE_3D,
        };
        let view = make_view(view_type, 0, layers)?;
        ctx.set_name(view, &desc.name);
        let mut layer_views = Vec::new();
        if layers > 1 {
            for l in 0..layers {
                layer_views.push(make_view(vk::ImageViewType::TYPE_2D, l, 1)?);
            }
        }
        let array_view = if cube { Some(make_view(vk::ImageViewType::TYPE_2D_ARRAY, 0, layers)?) } else { None };
        Ok(Image {
            ctx: ctx.clone(),
            raw,
            view,
            layer_views,
            array_view,
            allocation: Some(allocation),
            desc: desc.clone(),
        })
    }

    pub fn extent(&self) -> vk::Extent2D {
        vk::Extent2D { width: self.desc.width, height: self.desc.height }
    }
    pub fn format(&self) -> vk::Format {
        self.desc.format
    }
    pub fn aspect(&self) -> vk::ImageAspectFlags {
        aspect_of(self.desc.format)
    }
    pub fn name(&self) -> &str {
        &self.desc.name
    }
    pub fn layers(&self) -> u32 {
        self.desc.layers.max(1)
    }
    /// Texels along z (1 unless the image is 3D).
    pub fn depth(&self) -> u32 {
        self.desc.depth()
    }
    /// The view over all layers.
    pub fn view(&self) -> vk::ImageView {
        self.view
    }
    /// A 2D view of one layer (the whole image if it has one layer).
    pub fn layer_view(&self, layer: u32) -> vk::ImageView {
        if self.layer_views.is_empty() {
            self.view
        } else {
            self.layer_views[layer as usize]
        }
    }
    /// A 2D-array view over all layers of a cube-compatible image.
    pub fn array_view(&self) -> vk::ImageView {
        self.array_view.unwrap_or(self.view)
    }
}

impl Drop for Image {
    fn drop(&mut self) {
        if let Some(a) = self.allocation.take() {
            self.ctx.track(memory_kind(&self.desc), a.size(), false);
            let mut views = vec![self.view];
            views.append(&mut self.layer_views);
            views.extend(self.array_view.take());
            self.ctx.defer_destroy(Garbage::Image(self.raw, views, a));
        }
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct SamplerDesc {
    pub filter: vk::Filter,
    pub address_u: vk::SamplerAddressMode,
    pub address_v: vk::SamplerAddressMode,
}

impl SamplerDesc {
    pub const NEAREST_CLAMP: SamplerDesc = SamplerDesc {
        filter: vk::Filter::NEAREST,
        address_u: vk::SamplerAddressMode::CLAMP_TO_EDGE,
        address_v: vk::SamplerAddressMode::CLAMP_TO_EDGE,
    };
    pub const LINEAR_CLAMP: SamplerDesc = SamplerDesc {
        filter: vk::Filter::LINEAR,
        address_u: vk::SamplerAddressMode::CLAMP_TO_EDGE,
        address_v: vk::SamplerAddressMode::CLAMP_TO_EDGE,
    };
    /// Latitude-longitude maps wrap in u (longitude) and clamp in v (poles).
    pub const LATLONG: SamplerDesc = SamplerDesc {
        filter: vk::Filter::LINEAR,
        address_u: vk::SamplerAddressMode::REPEAT,
        address_v: vk::SamplerAddressMode::CLAMP_TO_EDGE,
    };
}

/// The `VkSampler` every [`Sampler`] of one description shares; destroyed with the last of
/// them. The context's cache holds it weakly.
pub(crate) struct SharedSampler {
    ctx: Arc<GpuContext>,
    raw: vk::Sampler,
}

destroy_on_drop!(SharedSampler => destroy_sampler);

pub struct Sampler {
    _shared: Arc<SharedSampler>,
    pub(crate) raw: vk::Sampler,
}

impl Sampler {
    /// The sampler of `desc`: the cached one if a live sampler has the same description,
    /// else a new one named `name`.
    pub fn new(ctx: &Arc<GpuContext>, name: &str, desc: SamplerDesc) -> GpuResult<Sampler> {
        let (shared, _) = ctx.shared(desc, || {
            let info = vk::SamplerCreateInfo::default()
                .mag_filter(desc.filter)
                .min_filter(desc.filter)
                .mipmap_mode(vk::SamplerMipmapMode::NEAREST)
                .address_mode_u(desc.address_u)
                .address_mode_v(desc.address_v)
                .address_mode_w(vk::SamplerAddressMode::CLAMP_TO_EDGE)
                .max_lod(0.0);
            // SAFETY: valid create info.
            let raw = unsafe { ctx.raw().create_sampler(&info, None) }.vk("vkCreateSampler")?;
            ctx.set_name(raw, name);
            Ok(SharedSampler { ctx: ctx.clone(), raw })
        })?;
        Ok(Sampler { raw: shared.raw, _shared: shared })
    }
}
