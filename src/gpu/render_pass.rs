//! Explicit `VkRenderPass` objects described by a small key (wgpu-hal's `RenderPassKey`),
//! cached by that key: passes with the same attachments share one `VkRenderPass`.
//! Initial layout = final layout = the attachment layout; the frame graph does every
//! transition outside the pass (kajiya), so a pass never changes a layout behind its back.
use std::sync::Arc;

use ash::vk;

use super::context::GpuContext;
use super::error::{GpuError, GpuResult, VkContext};
use super::image::{aspect_of, Image};

#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Attachment {
    pub format: vk::Format,
    /// Clear on load (true) or keep the previous contents (false).
    pub clear: bool,
}

#[derive(Clone, Debug, PartialEq, Eq, Hash, Default)]
pub struct RenderPassDesc {
    pub colors: Vec<Attachment>,
    pub depth: Option<Attachment>,
    /// The depth attachment is only tested, not written (read-only layout).
    pub depth_read_only: bool,
}

/// The `VkRenderPass` every [`RenderPass`] of one description shares; destroyed with the
/// last of them. The context's cache holds it weakly.
pub(crate) struct SharedRenderPass {
    ctx: Arc<GpuContext>,
    raw: vk::RenderPass,
}

destroy_on_drop!(SharedRenderPass => destroy_render_pass, Framebuffer => destroy_framebuffer);

pub struct RenderPass {
    _shared: Arc<SharedRenderPass>,
    pub(crate) raw: vk::RenderPass,
    pub desc: RenderPassDesc,
}

impl RenderPass {
    /// The render pass of `desc`: the cached one if a live pass has the same description,
    /// else a new one named `name` (the debug name of the first creator).
    pub(super) fn new(ctx: &Arc<GpuContext>, name: &str, desc: &RenderPassDesc) -> GpuResult<RenderPass> {
        let (shared, _) = ctx.shared(desc.clone(), || {
            let load = |a: &Attachment| {
                if a.clear {
                    vk::AttachmentLoadOp::CLEAR
                } else {
                    vk::AttachmentLoadOp::LOAD
                }
            };
            let mut attachments = Vec::new();
            let mut color_refs = Vec::new();
            for (i, c) in desc.colors.iter().enumerate() {
                attachments.push(
                    vk::AttachmentDescription::default()
                        .format(c.format)
                        .samples(vk::SampleCountFlags::TYPE_1)
                        .load_op(load(c))
                        .store_op(vk::AttachmentStoreOp::STORE)
                        .stencil_load_op(vk::AttachmentLoadOp::DONT_CARE)
                        .stencil_store_op(vk::AttachmentStoreOp::DONT_CARE)
                        .initial_layout(vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL)
                        .final_layout(vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL),
                );
                color_refs.push(vk::AttachmentReference {
                    attachment: i as u32,
                    layout: vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL,
                });
            }
            let depth_layout = if desc.depth_read_only {
                vk::ImageLayout::DEPTH_STENCIL_READ_ONLY_OPTIMAL
            } else {
                vk::ImageLayout::DEPTH_STENCIL_ATTACHMENT_OPTIMAL
            };
            let depth_ref = desc.depth.map(|d| {
                let has_stencil = aspect_of(d.format).contains(vk::ImageAspectFlags::STENCIL);
                attachments.push(
                    vk::AttachmentDescription::default()
                        .format(d.format)
                        .samples(vk::SampleCountFlags::TYPE_1)
                        .load_op(load(&d))
                        .store_op(vk::AttachmentStoreOp::STORE)
                        .stencil_load_op(if has_stencil { load(&d) } else { vk::AttachmentLoadOp::DONT_CARE })
                        .stencil_store_op(vk::AttachmentStoreOp::DONT_CARE)
                        .initial_layout(depth_layout)
                        .final_layout(depth_layout),
                );
                vk::AttachmentReference { attachment: desc.colors.len() as u32, layout: depth_layout }
            });
            let mut subpass = vk::SubpassDescription::default()
                .pipeline_bind_point(vk::PipelineBindPoint::GRAPHICS)
                .color_attachments(&color_refs);
            if let Some(d) = depth_ref.as_ref() {
                subpass = subpass.depth_stencil_attachment(d);
            }
            let subpasses = [subpass];
            let info = vk::RenderPassCreateInfo::default().attachments(&attachments).subpasses(&subpasses);
            // SAFETY: valid create info; referenced arrays live for the call.
            let raw = unsafe { ctx.raw().create_render_pass(&info, None) }.vk("vkCreateRenderPass")?;
            ctx.set_name(raw, name);
            Ok(SharedRenderPass { ctx: ctx.clone(), raw })
        })?;
        Ok(RenderPass { raw: shared.raw, _shared: shared, desc: desc.clone() })
    }
}

pub struct Framebuffer {
    ctx: Arc<GpuContext>,
    pub(crate) raw: vk::Framebuffer,
    pub extent: vk::Extent2D,
}

impl Framebuffer {
    /// `views` in attachment order (colours, then depth).
    pub(super) fn new(
        ctx: &Arc<GpuContext>,
        name: &str,
        pass: &RenderPass,
        views: &[vk::ImageView],
        extent: vk::Extent2D,
    ) -> GpuResult<Framebuffer> {
        let info = vk::FramebufferCreateInfo::default()
            .render_pass(pass.raw)
            .attachments(views)
            .width(extent.width)
            .height(extent.height)
            .layers(1);
        // SAFETY: views match the pass's attachments.
        let raw = unsafe { ctx.raw().create_framebuffer(&info, None) }.vk("vkCreateFramebuffer")?;
        ctx.set_name(raw, name);
        Ok(Framebuffer { ctx: ctx.clone(), raw, extent })
    }
}

/// A render pass and its framebuffers over a set of images: one framebuffer over their
/// default views, or one per layer over that layer of each (cube faces, array layers).
pub struct RenderTarget {
    pub pass: RenderPass,
    framebuffers: Vec<Framebuffer>,
}

impl RenderTarget {
    /// Colour attachments `colors` and an optional depth attachment, every one cleared on
    /// load (`clear`) or keeping what earlier passes wrote; one framebuffer.
    pub fn new(
        ctx: &Arc<GpuContext>,
        name: &str,
        colors: &[&Image],
        depth: Option<&Image>,
        clear: bool,
    ) -> GpuResult<RenderTarget> {
        let colors: Vec<_> = colors.iter().map(|&i| (i, clear)).collect();
        Self::build(ctx, name, &colors, depth.map(|d| (d, clear)), None)
    }

    /// As [`Self::new`] without depth, each colour attachment cleared or kept by its own
    /// flag (a pass that draws over a target and fills debug targets of its own).
    pub fn with_clears(ctx: &Arc<GpuContext>, name: &str, colors: &[(&Image, bool)]) -> GpuResult<RenderTarget> {
        Self::build(ctx, name, colors, None, None)
    }

    /// As [`Self::new`], with framebuffer `l` over layer `l` of every attachment, for `l` in
    /// `0..layers`.
    pub fn layered(
        ctx: &Arc<GpuContext>,
        name: &str,
        colors: &[&Image],
        depth: Option<&Image>,
        clear: bool,
        layers: u32,
    ) -> GpuResult<RenderTarget> {
        let colors: Vec<_> = colors.iter().map(|&i| (i, clear)).collect();
        Self::build(ctx, name, &colors, depth.map(|d| (d, clear)), Some(layers))
    }

    /// As [`Self::new`], with framebuffer `i` over the colour images and depth image of
    /// `sets[i]`, all of the formats and extent of the first (one light's maps each).
    pub fn each(
        ctx: &Arc<GpuContext>,
        name: &str,
        sets: &[(Vec<&Image>, Option<&Image>)],
        clear: bool,
    ) -> GpuResult<RenderTarget> {
        let Some((colors, depth)) = sets.first() else {
            return Err(GpuError::Unsupported(format!("{name}: a render target without framebuffers")));
        };
        let mut target = Self::new(ctx, name, colors, *depth, clear)?;
        for (i, (colors, depth)) in sets.iter().enumerate().skip(1) {
            let views: Vec<_> = colors.iter().copied().chain(*depth).map(|image| image.view()).collect();
            let extent = target.framebuffers[0].extent;
            target.framebuffers.push(Framebuffer::new(ctx, &format!("{name}_{i}"), &target.pass, &views, extent)?);
        }
        Ok(target)
    }

    fn build(
        ctx: &Arc<GpuContext>,
        name: &str,
        colors: &[(&Image, bool)],
        depth: Option<(&Image, bool)>,
        layers: Option<u32>,
    ) -> GpuResult<RenderTarget> {
        let attachment = |&(i, clear): &(&Image, bool)| Attachment { format: i.format(), clear };
        let desc = RenderPassDesc {
            colors: colors.iter().map(attachment).collect(),
            depth: depth.as_ref().map(attachment),
            depth_read_only: false,
        };
        let pass = RenderPass::new(ctx, name, &desc)?;
        let attachments: Vec<&Image> = colors.iter().chain(&depth).map(|&(i, _)| i).collect();
        let extent = attachments.first().map_or(vk::Extent2D { width: 1, height: 1 }, |i| i.extent());
        let framebuffers = match layers {
            None => {
                let views: Vec<_> = attachments.iter().map(|i| i.view()).collect();
                vec![Framebuffer::new(ctx, name, &pass, &views, extent)?]
            }
            Some(n) => (0..n)
                .map(|l| {
                    let views: Vec<_> = attachments.iter().map(|i| i.layer_view(l)).collect();
                    Framebuffer::new(ctx, &format!("{name}_{l}"), &pass, &views, extent)
                })
                .collect::<GpuResult<_>>()?,
        };
        Ok(RenderTarget { pass, framebuffers })
    }

    pub fn framebuffers(&self) -> &[Framebuffer] {
        &self.framebuffers
    }

    /// The size of its attachments (every layer's the same).
    pub fn extent(&self) -> vk::Extent2D {
        self.framebuffers[0].extent
    }
}
