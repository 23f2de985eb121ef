//! Render targets of a frame, registered with the frame graph.
use std::sync::Arc;

use crate::gpu::{vk, GpuContext, Image, ImageDesc, ImageViewKind, Sampler};
use crate::graph::{Bindings, FrameGraph, ImageId};
use crate::{BINDING_GBUF_ALBEDO, BINDING_GBUF_DEPTH, BINDING_GBUF_NORMAL, SHADOW_LAYERS_PER_LIGHT};

use super::RenderError;

/// Formats, chosen for measurement rather than bandwidth: radiance is 32-bit float so that
/// error metrics see the technique's error, not the storage's.
pub const HDR_FORMAT: vk::Format = vk::Format::R32G32B32A32_SFLOAT;
pub const LDR_FORMAT: vk::Format = vk::Format::R8G8B8A8_UNORM;
pub const GBUF_NORMAL_FORMAT: vk::Format = vk::Format::R16G16B16A16_SFLOAT;
pub const GBUF_ALBEDO_FORMAT: vk::Format = vk::Format::R16G16B16A16_SFLOAT;
pub const DEPTH_FORMAT: vk::Format = vk::Format::D32_SFLOAT;
pub const SHADOW_FORMAT: vk::Format = vk::Format::R32_SFLOAT;
/// Caustic map: flux per texel in W, RGB (Shah et al. 2007; src/technique/caustics/caustics_map.rs).
pub const CAUSTIC_FORMAT: vk::Format = vk::Format::R32G32B32A32_SFLOAT;

pub struct Targets {
    pub width: u32,
    pub height: u32,
    /// Lights with layers in the shadow and caustic atlases (0: the 1x1 stand-ins).
    pub shadow_lights: u32,
    pub gbuf_normal: Image,
    pub gbuf_albedo: Image,
    pub depth: Image,
    pub hdr: Image,
    pub ldr: Image,
    /// Distance-to-light atlas: SHADOW_LAYERS_PER_LIGHT layers per light, cube-compatible.
    /// The atlases are shared with the targets of the next image size (see [`Targets::resized`]).
    pub shadow_atlas: Arc<Image>,
    /// One depth layer per atlas layer, so faces never wait on each other's depth buffer.
    pub shadow_depth: Arc<Image>,
    /// Caustic-map atlas and its receivers' distances, laid out like `shadow_atlas`.
    pub caustic: CausticAtlas,
    pub gbuf_normal_id: ImageId,
    pub gbuf_albedo_id: ImageId,
    pub depth_id: ImageId,
    pub hdr_id: ImageId,
    pub ldr_id: ImageId,
    pub shadow_atlas_id: ImageId,
    pub shadow_depth_id: ImageId,
}

/// The caustic map of Shah et al. 2007 (src/technique/caustics/caustics_map.rs) and the
/// receivers it was splatted onto, both laid out like the shadow atlas (six cube-compatible
/// layers per light); cleared 1x1 stand-ins when no caustics-mapping pass writes them.
#[derive(Clone)]
pub struct CausticAtlas {
    /// Flux per texel in W, RGB.
    pub flux: Arc<Image>,
    pub flux_id: ImageId,
    /// Distance from the light to the nearest diffuse receiver (the refractors left out), per
    /// texel, as the shadow maps store it: the surface the texel's flux fell on. A receiver
    /// further from the light behind it is hidden from the caustic.
    pub receivers: Arc<Image>,
    pub receivers_id: ImageId,
}

/// The light-space images of [`Targets`], which do not depend on the image size.
struct Atlases {
    shadow_lights: u32,
    shadow_atlas: Arc<Image>,
    shadow_depth: Arc<Image>,
    caustic: CausticAtlas,
    shadow_atlas_id: ImageId,
    shadow_depth_id: ImageId,
}

impl Targets {
    pub fn new(
        ctx: &Arc<GpuContext>,
        graph: &mut FrameGraph,
        width: u32,
        height: u32,
        lights: u32,
        shadow_size: u32,
        caustic_size: Option<u32>,
    ) -> Result<Targets, RenderError> {
        if shadow_size == 0 || shadow_size > ctx.limits().max_image_dimension_cube {
            return Err(RenderError::Limit(format!(
                "render.shadow_map_size = {shadow_size} is outside 1..={}",
                ctx.limits().max_image_dimension_cube
            )));
        }
        use vk::ImageUsageFlags as U;
        // Without lights the atlas is a 1x1 stand-in that is still bound (and cleared).
        let (size, layers) =
            if lights == 0 { (1, SHADOW_LAYERS_PER_LIGHT) } else { (shadow_size, lights * SHADOW_LAYERS_PER_LIGHT) };
        let layered = |name: &str, format, usage, view| ImageDesc {
            name: name.into(),
            format,
            width: size,
            height: size,
            layers,
            usage,
            view,
        };
        let shadow_atlas = Image::new(
            ctx,
            &layered(
                "shadow_atlas",
                SHADOW_FORMAT,
                U::COLOR_ATTACHMENT | U::SAMPLED | U::TRANSFER_DST | U::TRANSFER_SRC,
                ImageViewKind::CubeArray,
            ),
        )?;
        let shadow_depth = Image::new(
            ctx,
            &layered("shadow_depth", DEPTH_FORMAT, U::DEPTH_STENCIL_ATTACHMENT, ImageViewKind::D2Array),
        )?;
        let caustic = Self::caustic_atlas(ctx, graph, lights, caustic_size)?;
        let atlases = Atlases {
            shadow_lights: lights,
            shadow_atlas_id: graph.register_image(&shadow_atlas),
            shadow_depth_id: graph.register_image(&shadow_depth),
            shadow_atlas: Arc::new(shadow_atlas),
            shadow_depth: Arc::new(shadow_depth),
            caustic,
        };
        Self::with_atlases(ctx, graph, width, height, atlases)
    }

    /// The image-sized targets made anew at `width` x `height`, around the same atlases: they
    /// do not depend on the image size, and keep what the light-space passes wrote.
    pub fn resized(
        &self,
        ctx: &Arc<GpuContext>,
        graph: &mut FrameGraph,
        width: u32,
        height: u32,
    ) -> Result<Targets, RenderError> {
        let atlases = Atlases {
            shadow_lights: self.shadow_lights,
            shadow_atlas: self.shadow_atlas.clone(),
            shadow_depth: self.shadow_depth.clone(),
            caustic: self.caustic.clone(),
            shadow_atlas_id: self.shadow_atlas_id,
            shadow_depth_id: self.shadow_depth_id,
        };
        Self::with_atlases(ctx, graph, width, height, atlases)
    }

    fn with_atlases(
        ctx: &Arc<GpuContext>,
        graph: &mut FrameGraph,
        width: u32,
        height: u32,
        a: Atlases,
    ) -> Result<Targets, RenderError> {
        let max = ctx.limits().max_image_dimension2_d;
        if width == 0 || height == 0 || width > max || height > max {
            return Err(RenderError::Limit(format!(
                "image size {width}x{height} is outside 1..={max} (the device's maxImageDimension2D)"
            )));
        }
        use vk::ImageUsageFlags as U;
        let attach_sampled = U::COLOR_ATTACHMENT | U::SAMPLED | U::TRANSFER_SRC;
        let mk = |name: &str, format, usage| Image::new(ctx, &ImageDesc::d2(name, format, width, height, usage));
        let gbuf_normal = mk("gbuf_normal", GBUF_NORMAL_FORMAT, attach_sampled)?;
        let gbuf_albedo = mk("gbuf_albedo", GBUF_ALBEDO_FORMAT, attach_sampled)?;
        let depth = mk("depth", DEPTH_FORMAT, U::DEPTH_STENCIL_ATTACHMENT | U::SAMPLED | U::TRANSFER_SRC)?;
        let hdr = mk("hdr", HDR_FORMAT, attach_sampled | U::STORAGE)?;
        let ldr = mk("ldr", LDR_FORMAT, U::COLOR_ATTACHMENT | U::TRANSFER_SRC)?;
        Ok(Targets {
            width,
            height,
            shadow_lights: a.shadow_lights,
            gbuf_normal_id: graph.register_image(&gbuf_normal),
            gbuf_albedo_id: graph.register_image(&gbuf_albedo),
            depth_id: graph.register_image(&depth),
            hdr_id: graph.register_image(&hdr),
            ldr_id: graph.register_image(&ldr),
            shadow_atlas_id: a.shadow_atlas_id,
            shadow_depth_id: a.shadow_depth_id,
            gbuf_normal,
            gbuf_albedo,
            depth,
            hdr,
            ldr,
            shadow_atlas: a.shadow_atlas,
            shadow_depth: a.shadow_depth,
            caustic: a.caustic,
        })
    }

    /// The image-sized targets, which the light-space stages never touch
    /// ([`crate::technique::Stage::is_image_space`]).
    pub fn image_sized(&self) -> [ImageId; 5] {
        [self.gbuf_normal_id, self.gbuf_albedo_id, self.depth_id, self.hdr_id, self.ldr_id]
    }

    /// Put `atlas` in place of the caustic atlas, and return the one it replaces (to swap
    /// back, or to drop once the GPU is done with it).
    pub fn swap_caustic_atlas(&mut self, atlas: CausticAtlas) -> CausticAtlas {
        std::mem::replace(&mut self.caustic, atlas)
    }

    /// The caustic-map atlas and its receivers: six cube-compatible layers of `caustic_size`
    /// per light, or 1x1 stand-ins when no caustics-mapping pass writes them (they are bound
    /// all the same), registered with `graph`.
    pub fn caustic_atlas(
        ctx: &Arc<GpuContext>,
        graph: &mut FrameGraph,
        lights: u32,
        caustic_size: Option<u32>,
    ) -> Result<CausticAtlas, RenderError> {
        let (size, layers) = match caustic_size {
            Some(c) if lights > 0 => (c, lights * SHADOW_LAYERS_PER_LIGHT),
            _ => (1, SHADOW_LAYERS_PER_LIGHT),
        };
        if size > ctx.limits().max_image_dimension_cube {
            return Err(RenderError::Limit(format!(
                "render.caustics_map.map_size = {size} is above the device's maximum cube size {}",
                ctx.limits().max_image_dimension_cube
            )));
        }
        use vk::ImageUsageFlags as U;
        let image = |name: &str, format| {
            Image::new(
                ctx,
                &ImageDesc {
                    name: name.into(),
                    format,
                    width: size,
                    height: size,
                    layers,
                    usage: U::COLOR_ATTACHMENT | U::SAMPLED | U::TRANSFER_DST | U::TRANSFER_SRC,
                    view: ImageViewKind::CubeArray,
                },
            )
        };
        let flux = image("caustic_atlas", CAUSTIC_FORMAT)?;
        let receivers = image("caustic_receivers", SHADOW_FORMAT)?;
        Ok(CausticAtlas {
            flux_id: graph.register_image(&flux),
            receivers_id: graph.register_image(&receivers),
            flux: Arc::new(flux),
            receivers: Arc::new(receivers),
        })
    }

    /// The G-buffer's normal and depth (and, with `albedo`, its albedo) at their shared
    /// bindings, fetched per texel with `nearest` and read by the passes using the set.
    pub fn gbuffer<'a>(&'a self, b: Bindings<'a>, nearest: &'a Sampler, albedo: bool) -> Bindings<'a> {
        let b = b.sampled(BINDING_GBUF_NORMAL, &self.gbuf_normal, nearest).read(self.gbuf_normal_id);
        let b = if albedo {
            b.sampled(BINDING_GBUF_ALBEDO, &self.gbuf_albedo, nearest).read(self.gbuf_albedo_id)
        } else {
            b
        };
        b.sampled(BINDING_GBUF_DEPTH, &self.depth, nearest).read(self.depth_id)
    }

    pub fn extent(&self) -> vk::Extent2D {
        vk::Extent2D { width: self.width, height: self.height }
    }
}
