//! The demo's heads-up overlay: egui primitives drawn onto a swapchain image by
//! `egui-ash-renderer`, inside a render pass of our own that loads the image (the scene was
//! blitted there first) and keeps it in COLOR_ATTACHMENT_OPTIMAL, like every render pass
//! here: the frame graph does the transitions around it.
use std::sync::Arc;

use ash::vk;
use egui_ash_renderer::{Options, Renderer};

use super::command::Cmd;
use super::context::GpuContext;
use super::error::{GpuError, GpuResult, VkContext};
use super::render_pass::{Attachment, Framebuffer, RenderPass, RenderPassDesc};
use super::swapchain::Swapchain;
use super::Clear;

pub struct Overlay {
    // Drop order: the egui renderer (pipelines, buffers, textures), then the objects it uses.
    renderer: Renderer,
    framebuffers: Vec<Framebuffer>,
    render_pass: RenderPass,
    /// Pool for egui's texture uploads (font atlas), which it submits and waits for itself.
    upload_pool: vk::CommandPool,
    /// Textures egui freed, released once no frame in flight can still sample them.
    to_free: Vec<egui::TextureId>,
    ctx: Arc<GpuContext>,
}

fn overlay_error(e: egui_ash_renderer::RendererError) -> GpuError {
    GpuError::Overlay(e.to_string())
}

impl Overlay {
    /// An overlay for the images of `swapchain`; `frames_in_flight` as the renderer's.
    pub fn new(ctx: &Arc<GpuContext>, swapchain: &Swapchain, frames_in_flight: usize) -> GpuResult<Overlay> {
        let render_pass = RenderPass::new(
            ctx,
            "overlay",
            &RenderPassDesc {
                colors: vec![Attachment { format: swapchain.format(), clear: false }],
                ..Default::default()
            },
        )?;
        let options = Options {
            in_flight_frames: frames_in_flight,
            enable_depth_test: false,
            enable_depth_write: false,
            // The swapchain is UNORM (see swapchain.rs): egui's shader encodes sRGB itself.
            srgb_framebuffer: false,
        };
        let renderer =
            Renderer::with_default_allocator(&ctx.instance, ctx.physical, ctx.device.clone(), render_pass.raw, options)
                .map_err(overlay_error)?;
        let pool_info = vk::CommandPoolCreateInfo::default()
            .queue_family_index(ctx.queue_family)
            .flags(vk::CommandPoolCreateFlags::RESET_COMMAND_BUFFER | vk::CommandPoolCreateFlags::TRANSIENT);
        // SAFETY: valid device and create info.
        let upload_pool = unsafe { ctx.device.create_command_pool(&pool_info, None) }.vk("vkCreateCommandPool")?;
        ctx.set_name(upload_pool, "overlay_upload_pool");
        let mut overlay = Overlay {
            renderer,
            framebuffers: Vec::new(),
            render_pass,
            upload_pool,
            to_free: Vec::new(),
            ctx: ctx.clone(),
        };
        overlay.set_targets(swapchain)?;
        Ok(overlay)
    }

    /// Framebuffers for the current images of `swapchain` (after it was recreated). The
    /// swapchain's format never changes between recreations (swapchain.rs picks from a fixed
    /// list in a fixed order), so the render pass and pipeline stay valid.
    pub fn set_targets(&mut self, swapchain: &Swapchain) -> GpuResult<()> {
        self.ctx.wait_idle()?;
        self.framebuffers.clear();
        if self.render_pass.desc.colors[0].format != swapchain.format() && swapchain.is_ready() {
            return Err(GpuError::Unsupported(format!(
                "the swapchain format changed from {:?} to {:?}",
                self.render_pass.desc.colors[0].format,
                swapchain.format()
            )));
        }
        for (i, image) in swapchain.images().iter().enumerate() {
            self.framebuffers.push(Framebuffer::new(
                &self.ctx,
                &format!("overlay_fb_{i}"),
                &self.render_pass,
                &[image.view],
                swapchain.extent(),
            )?);
        }
        Ok(())
    }

    /// Upload the textures egui created or changed this frame (before recording), and
    /// remember the ones it freed.
    pub fn update_textures(&mut self, delta: &egui::TexturesDelta) -> GpuResult<()> {
        if !delta.set.is_empty() {
            self.renderer.set_textures(self.ctx.queue, self.upload_pool, &delta.set).map_err(overlay_error)?;
        }
        self.to_free.extend_from_slice(&delta.free);
        Ok(())
    }

    /// Free the textures egui gave up. Rare (font atlas growth), so it simply waits for the
    /// device to be idle: no frame in flight samples them any more.
    pub fn free_textures(&mut self) -> GpuResult<()> {
        if self.to_free.is_empty() {
            return Ok(());
        }
        self.ctx.wait_idle()?;
        let ids = std::mem::take(&mut self.to_free);
        self.renderer.free_textures(&ids).map_err(overlay_error)
    }

    /// Draw `primitives` onto swapchain image `image` (in COLOR_ATTACHMENT_OPTIMAL).
    pub fn record(
        &mut self,
        cmd: &Cmd,
        image: usize,
        pixels_per_point: f32,
        primitives: &[egui::ClippedPrimitive],
    ) -> GpuResult<()> {
        let fb = &self.framebuffers[image];
        let extent = fb.extent;
        let renderer = &mut self.renderer;
        cmd.in_render_pass(&self.render_pass, fb, &[Clear::None], |cmd| {
            renderer.cmd_draw(cmd.raw, extent, pixels_per_point, primitives).map_err(overlay_error)
        })
    }
}

impl Drop for Overlay {
    fn drop(&mut self) {
        let _ = self.ctx.wait_idle();
        if !self.to_free.is_empty() {
            let ids = std::mem::take(&mut self.to_free);
            let _ = self.renderer.free_textures(&ids);
        }
        // SAFETY: the device is idle; the pool's command buffers were freed by egui's
        // uploader after each use.
        unsafe { self.ctx.device.destroy_command_pool(self.upload_pool, None) };
    }
}
