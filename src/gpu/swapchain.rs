//! Window surface, swapchain and the semaphores of presentation: the only module with
//! surface and swapchain calls (the demo window, `prism demo`).
//!
//! Frames in flight: the acquire semaphore belongs to the renderer's frame slot (it is free
//! again once that slot's fence has signalled, which the caller waits for before acquiring);
//! the render-done semaphore belongs to the swapchain image, because the presentation engine
//! may still wait on it after the slot's fence has signalled.
use std::sync::Arc;

use ash::vk;
use raw_window_handle::{HasDisplayHandle, HasWindowHandle};

use super::context::{timeout_nanos, GpuContext, FRAME_TIMEOUT};
use super::error::{GpuError, GpuResult, VkContext};

/// The swapchain's colour format. UNORM, not SRGB: the renderer's LDR image already holds
/// sRGB-encoded values, so they are copied as they are (and egui draws in gamma space).
const FORMATS: [vk::Format; 2] = [vk::Format::B8G8R8A8_UNORM, vk::Format::R8G8B8A8_UNORM];

/// A binary semaphore, destroyed with its owner after the device is idle.
pub struct Semaphore {
    ctx: Arc<GpuContext>,
    pub raw: vk::Semaphore,
}

impl Semaphore {
    pub fn new(ctx: &Arc<GpuContext>, name: &str) -> GpuResult<Semaphore> {
        // SAFETY: valid device and default create info.
        let raw =
            unsafe { ctx.raw().create_semaphore(&vk::SemaphoreCreateInfo::default(), None) }.vk("vkCreateSemaphore")?;
        ctx.set_name(raw, name);
        Ok(Semaphore { ctx: ctx.clone(), raw })
    }
}

destroy_on_drop!(Semaphore => destroy_semaphore);

/// One image of the swapchain and its view.
#[derive(Clone, Copy, Debug)]
pub struct SwapchainImage {
    pub raw: vk::Image,
    pub view: vk::ImageView,
}

/// What [`Swapchain::acquire`] got.
#[derive(Debug)]
pub enum Acquired {
    /// Image `index` is ours once `wait` has signalled; the frame's submission signals
    /// `render_done`, which presentation waits for.
    Image { index: u32, wait: vk::Semaphore, render_done: vk::Semaphore, suboptimal: bool },
    /// The swapchain no longer matches the surface (resized): recreate it and try again.
    OutOfDate,
}

/// What presenting found out about the swapchain.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Presented {
    Ok,
    /// Presented, but the swapchain should be recreated (suboptimal or out of date).
    Stale,
}

pub struct Swapchain {
    ctx: Arc<GpuContext>,
    surface_fn: ash::khr::surface::Instance,
    surface: vk::SurfaceKHR,
    swapchain_fn: ash::khr::swapchain::Device,
    raw: vk::SwapchainKHR,
    images: Vec<SwapchainImage>,
    format: vk::Format,
    extent: vk::Extent2D,
    vsync: bool,
    present_mode: vk::PresentModeKHR,
    /// One per renderer frame slot.
    acquire: Vec<Semaphore>,
    /// One per swapchain image.
    render_done: Vec<Semaphore>,
}

impl Swapchain {
    /// Create a surface for `window` and a swapchain of `size` (the window's inner size in
    /// pixels). `vsync`: FIFO; otherwise MAILBOX or IMMEDIATE when available. `slots`: frames
    /// in flight. The context must come from [`GpuContext::for_display`].
    pub fn new(
        ctx: &Arc<GpuContext>,
        window: &(impl HasWindowHandle + HasDisplayHandle),
        size: (u32, u32),
        vsync: bool,
        slots: usize,
    ) -> GpuResult<Swapchain> {
        let surface_fn = ash::khr::surface::Instance::new(&ctx.entry, &ctx.instance);
        let surface = create_surface(ctx, &surface_fn, window)?;
        let mut acquire = Vec::new();
        for i in 0..slots {
            acquire.push(Semaphore::new(ctx, &format!("acquire_{i}"))?);
        }
        let mut chain = Swapchain {
            ctx: ctx.clone(),
            surface_fn,
            surface,
            swapchain_fn: ash::khr::swapchain::Device::new(&ctx.instance, &ctx.device),
            raw: vk::SwapchainKHR::null(),
            images: Vec::new(),
            format: vk::Format::UNDEFINED,
            extent: vk::Extent2D::default(),
            vsync,
            present_mode: vk::PresentModeKHR::FIFO,
            acquire,
            render_done: Vec::new(),
        };
        chain.recreate(size)?;
        Ok(chain)
    }

    /// (Re)create the swapchain for a window of `size`. Waits for the device to be idle
    /// first, so that no image, view or semaphore is still in use. Returns false (and keeps
    /// no swapchain) when the surface has a zero extent (a minimized window): the caller
    /// pauses until the window is restored.
    pub fn recreate(&mut self, size: (u32, u32)) -> GpuResult<bool> {
        self.ctx.wait_idle()?;
        // SAFETY: plain queries on a surface of this instance.
        let caps = unsafe { self.surface_fn.get_physical_device_surface_capabilities(self.ctx.physical, self.surface) }
            .map_err(surface_error("vkGetPhysicalDeviceSurfaceCapabilitiesKHR"))?;
        // SAFETY: as above.
        let formats = unsafe { self.surface_fn.get_physical_device_surface_formats(self.ctx.physical, self.surface) }
            .map_err(surface_error("vkGetPhysicalDeviceSurfaceFormatsKHR"))?;
        // SAFETY: as above.
        let modes =
            unsafe { self.surface_fn.get_physical_device_surface_present_modes(self.ctx.physical, self.surface) }
                .map_err(surface_error("vkGetPhysicalDeviceSurfacePresentModesKHR"))?;
        // currentExtent is the window's size when the platform fixes it (X11, Win32);
        // 0xFFFFFFFF means the swapchain decides (Wayland): the window's size, clamped.
        let extent = if caps.current_extent.width != u32::MAX {
            caps.current_extent
        } else {
            vk::Extent2D {
                width: size.0.clamp(caps.min_image_extent.width, caps.max_image_extent.width),
                height: size.1.clamp(caps.min_image_extent.height, caps.max_image_extent.height),
            }
        };
        self.destroy_images();
        if extent.width == 0 || extent.height == 0 {
            self.destroy_swapchain();
            return Ok(false);
        }
        let format = FORMATS
            .iter()
            .find_map(|f| formats.iter().find(|s| s.format == *f))
            .copied()
            .ok_or_else(|| GpuError::Unsupported(format!("the surface offers none of {FORMATS:?}: {formats:?}")))?;
        let usage = vk::ImageUsageFlags::TRANSFER_DST | vk::ImageUsageFlags::COLOR_ATTACHMENT;
        if !caps.supported_usage_flags.contains(usage) {
            return Err(GpuError::Unsupported(format!(
                "swapchain images cannot be blit targets and colour attachments ({:?})",
                caps.supported_usage_flags
            )));
        }
        let wanted: &[vk::PresentModeKHR] = if self.vsync {
            &[vk::PresentModeKHR::FIFO]
        } else {
            &[vk::PresentModeKHR::MAILBOX, vk::PresentModeKHR::IMMEDIATE, vk::PresentModeKHR::FIFO]
        };
        // FIFO is always supported.
        let present_mode = wanted.iter().copied().find(|m| modes.contains(m)).unwrap_or(vk::PresentModeKHR::FIFO);
        let mut count = caps.min_image_count + 1;
        if caps.max_image_count != 0 {
            count = count.min(caps.max_image_count);
        }
        let old = self.raw;
        let info = vk::SwapchainCreateInfoKHR::default()
            .surface(self.surface)
            .min_image_count(count)
            .image_format(format.format)
            .image_color_space(format.color_space)
            .image_extent(extent)
            .image_array_layers(1)
            .image_usage(usage)
            .image_sharing_mode(vk::SharingMode::EXCLUSIVE)
            .pre_transform(caps.current_transform)
            .composite_alpha(vk::CompositeAlphaFlagsKHR::OPAQUE)
            .present_mode(present_mode)
            .clipped(true)
            .old_swapchain(old);
        // SAFETY: valid create info; the old swapchain (if any) is retired by this call and
        // destroyed right after, the device being idle.
        let created = unsafe { self.swapchain_fn.create_swapchain(&info, None) };
        self.destroy_swapchain();
        self.raw = created.map_err(surface_error("vkCreateSwapchainKHR"))?;
        self.ctx.set_name(self.raw, "swapchain");
        // SAFETY: raw was just created.
        let raws = unsafe { self.swapchain_fn.get_swapchain_images(self.raw) }.vk("vkGetSwapchainImagesKHR")?;
        for (i, &raw) in raws.iter().enumerate() {
            let view_info = vk::ImageViewCreateInfo::default()
                .image(raw)
                .view_type(vk::ImageViewType::TYPE_2D)
                .format(format.format)
                .subresource_range(vk::ImageSubresourceRange {
                    aspect_mask: vk::ImageAspectFlags::COLOR,
                    base_mip_level: 0,
                    level_count: 1,
                    base_array_layer: 0,
                    layer_count: 1,
                });
            // SAFETY: raw is an image of this swapchain.
            let view = unsafe { self.ctx.device.create_image_view(&view_info, None) }.vk("vkCreateImageView")?;
            self.ctx.set_name(raw, &format!("swapchain_image_{i}"));
            self.images.push(SwapchainImage { raw, view });
            self.render_done.push(Semaphore::new(&self.ctx, &format!("render_done_{i}"))?);
        }
        self.format = format.format;
        self.extent = extent;
        self.present_mode = present_mode;
        Ok(true)
    }

    /// The surface was lost (VK_ERROR_SURFACE_LOST_KHR): destroy it with the swapchain and
    /// make new ones for `window`. Returns what [`Swapchain::recreate`] returns.
    pub fn recreate_surface(
        &mut self,
        window: &(impl HasWindowHandle + HasDisplayHandle),
        size: (u32, u32),
    ) -> GpuResult<bool> {
        self.ctx.wait_idle()?;
        self.destroy_images();
        self.destroy_swapchain();
        // SAFETY: the device is idle and the surface's swapchain was destroyed above.
        unsafe { self.surface_fn.destroy_surface(self.surface, None) };
        self.surface = vk::SurfaceKHR::null();
        self.surface = create_surface(&self.ctx, &self.surface_fn, window)?;
        self.recreate(size)
    }

    /// Whether a swapchain exists (false while the window is minimized).
    pub fn is_ready(&self) -> bool {
        self.raw != vk::SwapchainKHR::null()
    }

    pub fn images(&self) -> &[SwapchainImage] {
        &self.images
    }

    pub fn format(&self) -> vk::Format {
        self.format
    }

    pub fn extent(&self) -> vk::Extent2D {
        self.extent
    }

    pub fn present_mode(&self) -> vk::PresentModeKHR {
        self.present_mode
    }

    /// Acquire the next image for frame slot `slot`, whose fence the caller has waited for
    /// (so that the slot's acquire semaphore has no pending operation).
    pub fn acquire(&mut self, slot: usize) -> GpuResult<Acquired> {
        let wait = self.acquire[slot].raw;
        // SAFETY: raw is a live swapchain; the semaphore is unsignalled with no pending
        // operation (see above); no fence.
        let result = unsafe {
            self.swapchain_fn.acquire_next_image(self.raw, timeout_nanos(FRAME_TIMEOUT), wait, vk::Fence::null())
        };
        match result {
            Ok((index, suboptimal)) => {
                let render_done = self.render_done[index as usize].raw;
                Ok(Acquired::Image { index, wait, render_done, suboptimal })
            }
            Err(vk::Result::ERROR_OUT_OF_DATE_KHR) => Ok(Acquired::OutOfDate),
            Err(vk::Result::TIMEOUT | vk::Result::NOT_READY) => {
                Err(GpuError::Timeout { what: "the next swapchain image", seconds: FRAME_TIMEOUT.as_secs() })
            }
            Err(e) => Err(surface_error("vkAcquireNextImageKHR")(e)),
        }
    }

    /// Queue image `index` for presentation once its render-done semaphore has signalled.
    pub fn present(&mut self, index: u32) -> GpuResult<Presented> {
        let waits = [self.render_done[index as usize].raw];
        let chains = [self.raw];
        let indices = [index];
        let info = vk::PresentInfoKHR::default().wait_semaphores(&waits).swapchains(&chains).image_indices(&indices);
        // SAFETY: index was acquired from this swapchain and the submission that signals
        // the semaphore has been made; the queue is used from this thread only.
        match unsafe { self.swapchain_fn.queue_present(self.ctx.queue, &info) } {
            Ok(false) => Ok(Presented::Ok),
            Ok(true) | Err(vk::Result::ERROR_OUT_OF_DATE_KHR) => Ok(Presented::Stale),
            Err(e) => Err(surface_error("vkQueuePresentKHR")(e)),
        }
    }

    fn destroy_images(&mut self) {
        for image in self.images.drain(..) {
            // SAFETY: callers wait for the device to be idle first.
            unsafe { self.ctx.device.destroy_image_view(image.view, None) };
        }
        self.render_done.clear();
    }

    fn destroy_swapchain(&mut self) {
        if self.raw != vk::SwapchainKHR::null() {
            // SAFETY: the device is idle and the views of its images are destroyed.
            unsafe { self.swapchain_fn.destroy_swapchain(self.raw, None) };
            self.raw = vk::SwapchainKHR::null();
        }
    }
}

impl Drop for Swapchain {
    fn drop(&mut self) {
        let _ = self.ctx.wait_idle();
        self.destroy_images();
        self.destroy_swapchain();
        self.acquire.clear();
        // SAFETY: the swapchain created from the surface is destroyed above.
        unsafe { self.surface_fn.destroy_surface(self.surface, None) };
    }
}

/// A surface for `window`, checked for present support on the context's queue family.
fn create_surface(
    ctx: &GpuContext,
    surface_fn: &ash::khr::surface::Instance,
    window: &(impl HasWindowHandle + HasDisplayHandle),
) -> GpuResult<vk::SurfaceKHR> {
    let display = window.display_handle().map_err(|e| GpuError::Unsupported(format!("no display handle: {e}")))?;
    let handle = window.window_handle().map_err(|e| GpuError::Unsupported(format!("no window handle: {e}")))?;
    // SAFETY: the handles are valid for the window's lifetime, which the caller keeps
    // longer than the swapchain (the demo drops the swapchain before the window).
    let surface =
        unsafe { ash_window::create_surface(&ctx.entry, &ctx.instance, display.as_raw(), handle.as_raw(), None) }
            .vk("vkCreateSurfaceKHR")?;
    // SAFETY: surface was just created from this instance; queue_family is the device's.
    let supported = unsafe { surface_fn.get_physical_device_surface_support(ctx.physical, ctx.queue_family, surface) };
    if !matches!(supported, Ok(true)) {
        // SAFETY: nothing was created from the surface.
        unsafe { surface_fn.destroy_surface(surface, None) };
        return Err(GpuError::Unsupported(format!(
            "the device {} cannot present to this window (queue family {} has no present support)",
            ctx.info.name, ctx.queue_family
        )));
    }
    Ok(surface)
}

/// ERROR_SURFACE_LOST_KHR becomes [`GpuError::SurfaceLost`] (the demo recreates the
/// surface); anything else names the call.
fn surface_error(call: &'static str) -> impl Fn(vk::Result) -> GpuError {
    move |result| match result {
        vk::Result::ERROR_SURFACE_LOST_KHR => GpuError::SurfaceLost,
        result => GpuError::Vk { call, result },
    }
}
