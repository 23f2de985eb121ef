//! Images, their views, and samplers.
use std::sync::{Arc, Weak};

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
    /// Dropped with the image: the frame graph holds a [`Weak`] to it, so that it lists and
    /// reads back only images that still exist (a dropped image's handle may be reused).
    alive: Arc<()>,
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
            // Every image can be read back for inspection (`prism render --targets`,
            // FrameGraph::read_back_image); TRANSFER_SRC costs no memory on the implementations
            // prism runs on, and no image is a transient attachment.
            .usage(desc.usage | vk::ImageUsageFlags::TRANSFER_SRC)
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
            alive: Arc::new(()),
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
    /// Alive while this image is: what the frame graph checks before it reads the image.
    pub fn liveness(&self) -> Weak<()> {
        Arc::downgrade(&self.alive)
    }
    /// A 2D-array view over all layers of a cube-compatible image.
    pub fn array_view(&self) -> vk::ImageView {
        self.array_view.unwrap_or(self.view)
    }
}

/// How the texels of `format` read back: (channels, bytes per texel) of what
/// [`texels_to_f32`] decodes; for a depth/stencil format, its depth aspect alone (the aspect
/// [`read_aspect`] copies). `None`: a format prism cannot decode (compressed, packed, 64-bit).
pub fn texel_layout(format: vk::Format) -> Option<(u32, u32)> {
    use vk::Format as F;
    Some(match format {
        F::R8_UNORM => (1, 1),
        F::R8G8B8A8_UNORM | F::B8G8R8A8_UNORM | F::R8G8B8A8_SRGB | F::B8G8R8A8_SRGB => (4, 4),
        F::R16_SFLOAT | F::D16_UNORM => (1, 2),
        F::R16G16_SFLOAT => (2, 4),
        F::R16G16B16A16_SFLOAT => (4, 8),
        F::R32_SFLOAT | F::R32_UINT | F::D32_SFLOAT | F::D32_SFLOAT_S8_UINT => (1, 4),
        // The depth aspect of these copies as 32 bits per texel with the value in the low 24.
        F::X8_D24_UNORM_PACK32 | F::D24_UNORM_S8_UINT => (1, 4),
        F::R32G32_SFLOAT => (2, 8),
        F::R32G32B32_SFLOAT => (3, 12),
        F::R32G32B32A32_SFLOAT => (4, 16),
        _ => return None,
    })
}

/// The aspect a read-back copies: a buffer copy takes one aspect, and for depth/stencil
/// images the depth is what a person inspects.
pub fn read_aspect(format: vk::Format) -> vk::ImageAspectFlags {
    let aspect = aspect_of(format);
    if aspect.contains(vk::ImageAspectFlags::DEPTH) {
        vk::ImageAspectFlags::DEPTH
    } else {
        aspect
    }
}

/// Tightly packed texels of `format` (as copied by a read-back of [`read_aspect`]) as f32
/// channels in the order R, G, B, A: UNORM to [0, 1] (sRGB formats keep their encoded
/// values), half floats widened, `R32_UINT` converted (exact below 2^24). `None` for a
/// format [`texel_layout`] does not know.
pub fn texels_to_f32(format: vk::Format, bytes: &[u8]) -> Option<Vec<f32>> {
    use vk::Format as F;
    let (_, size) = texel_layout(format)?;
    let u32s = || bytes.chunks_exact(4).map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]));
    let u16s = || bytes.chunks_exact(2).map(|b| u16::from_le_bytes([b[0], b[1]]));
    Some(match format {
        F::R8_UNORM | F::R8G8B8A8_UNORM | F::R8G8B8A8_SRGB => bytes.iter().map(|&b| b as f32 / 255.0).collect(),
        F::B8G8R8A8_UNORM | F::B8G8R8A8_SRGB => {
            bytes.chunks_exact(size as usize).flat_map(|t| [t[2], t[1], t[0], t[3]].map(|b| b as f32 / 255.0)).collect()
        }
        F::R16_SFLOAT | F::R16G16_SFLOAT | F::R16G16B16A16_SFLOAT => u16s().map(f16_to_f32).collect(),
        F::D16_UNORM => u16s().map(|v| v as f32 / 65535.0).collect(),
        F::R32_UINT => u32s().map(|v| v as f32).collect(),
        F::X8_D24_UNORM_PACK32 | F::D24_UNORM_S8_UINT => {
            u32s().map(|v| (v & 0xff_ffff) as f32 / 0xff_ffff as f32).collect()
        }
        _ => u32s().map(f32::from_bits).collect(),
    })
}

/// IEEE 754 binary16 to binary32, exactly (subnormals, infinities and NaN included).
fn f16_to_f32(h: u16) -> f32 {
    let sign = ((h as u32) & 0x8000) << 16;
    let exp = ((h >> 10) & 0x1f) as u32;
    let mant = (h & 0x3ff) as u32;
    let bits = match (exp, mant) {
        (0, 0) => sign,
        // Subnormal: mant * 2^-24, exact in f32.
        (0, m) => {
            let v = m as f32 * (-24f32).exp2();
            return if sign != 0 { -v } else { v };
        }
        (0x1f, m) => sign | 0x7f80_0000 | (m << 13),
        (e, m) => sign | ((e + 112) << 23) | (m << 13),
    };
    f32::from_bits(bits)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn half_floats_widen_exactly() {
        for (h, f) in [(0x3c00, 1.0), (0xc000, -2.0), (0x7bff, 65504.0), (0x0001, 5.960_464_5e-8), (0x8000, -0.0)] {
            assert_eq!(f16_to_f32(h).to_bits(), f32::to_bits(f), "{h:#x}");
        }
        assert!(f16_to_f32(0x7c00).is_infinite() && f16_to_f32(0x7e00).is_nan());
    }

    #[test]
    fn texels_decode_in_rgba_order() {
        let bgra = texels_to_f32(vk::Format::B8G8R8A8_UNORM, &[0, 51, 255, 255]).unwrap();
        assert_eq!(bgra, [1.0, 0.2, 0.0, 1.0]);
        let d24 = texels_to_f32(vk::Format::X8_D24_UNORM_PACK32, &0xabff_ffffu32.to_le_bytes()).unwrap();
        assert_eq!(d24, [1.0]);
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
    pub address_w: vk::SamplerAddressMode,
    /// The colour beyond the edge with CLAMP_TO_BORDER.
    pub border: vk::BorderColor,
}

impl SamplerDesc {
    pub const NEAREST_CLAMP: SamplerDesc = SamplerDesc {
        filter: vk::Filter::NEAREST,
        address_u: vk::SamplerAddressMode::CLAMP_TO_EDGE,
        address_v: vk::SamplerAddressMode::CLAMP_TO_EDGE,
        address_w: vk::SamplerAddressMode::CLAMP_TO_EDGE,
        border: vk::BorderColor::FLOAT_TRANSPARENT_BLACK,
    };
    pub const LINEAR_CLAMP: SamplerDesc = SamplerDesc { filter: vk::Filter::LINEAR, ..SamplerDesc::NEAREST_CLAMP };
    /// Latitude-longitude maps wrap in u (longitude) and clamp in v (poles).
    pub const LATLONG: SamplerDesc =
        SamplerDesc { address_u: vk::SamplerAddressMode::REPEAT, ..SamplerDesc::LINEAR_CLAMP };
    /// Trilinear, zero beyond every face (a volume surrounded by nothing).
    pub const LINEAR_BORDER: SamplerDesc = SamplerDesc {
        filter: vk::Filter::LINEAR,
        address_u: vk::SamplerAddressMode::CLAMP_TO_BORDER,
        address_v: vk::SamplerAddressMode::CLAMP_TO_BORDER,
        address_w: vk::SamplerAddressMode::CLAMP_TO_BORDER,
        border: vk::BorderColor::FLOAT_TRANSPARENT_BLACK,
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
                .address_mode_w(desc.address_w)
                .border_color(desc.border)
                .max_lod(0.0);
            // SAFETY: valid create info.
            let raw = unsafe { ctx.raw().create_sampler(&info, None) }.vk("vkCreateSampler")?;
            ctx.set_name(raw, name);
            Ok(SharedSampler { ctx: ctx.clone(), raw })
        })?;
        Ok(Sampler { raw: shared.raw, _shared: shared })
    }
}
