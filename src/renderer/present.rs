//! Presentation: the window's two passes after the scene's, through the same frame graph and
//! timers: `present_blit` (the tone-mapped image onto the swapchain image) and `overlay` (the
//! egui heads-up display on top). The window decides what to show; only the renderer records.
use crate::gpu::{vk, Access, GpuError, Overlay, SubmitSync};
use crate::graph::ImageId;

use super::{RenderError, Renderer};

/// Pass names of the window's passes (listed apart from the scene's in the overlay).
pub const PRESENT_BLIT: &str = "present_blit";
pub const OVERLAY: &str = "overlay";

/// The swapchain image a frame is presented to.
pub struct WindowTarget {
    /// Its id in this renderer's frame graph, its handle, its size and its index in the
    /// swapchain.
    pub id: ImageId,
    pub raw: vk::Image,
    pub extent: vk::Extent2D,
    pub index: u32,
}

/// The overlay's triangles for this frame.
pub struct OverlayDraw<'a> {
    pub overlay: &'a mut Overlay,
    pub pixels_per_point: f32,
    pub primitives: &'a [egui::ClippedPrimitive],
}

impl Renderer {
    /// Record and submit one frame presented to `target`, with the overlay on top when given;
    /// `sync` waits for the image's acquisition and signals its presentation.
    pub fn render_to_window(
        &mut self,
        sync: &SubmitSync,
        target: &WindowTarget,
        overlay: Option<OverlayDraw<'_>>,
    ) -> Result<(), RenderError> {
        let (id, raw, extent, index) = (target.id, target.raw, target.extent, target.index);
        let mut overlay_result: Result<(), GpuError> = Ok(());
        let result = &mut overlay_result;
        self.render_frame_with(sync, |frame, fin| {
            frame
                .pass(PRESENT_BLIT)
                .read(fin.ldr_id, Access::TransferRead)
                .write(id, Access::TransferWrite)
                .record(move |cmd| cmd.blit_to(fin.ldr, raw, extent, vk::Filter::LINEAR));
            if let Some(o) = overlay {
                frame.pass(OVERLAY).write(id, Access::ColorAttachment).record(move |cmd| {
                    *result = o.overlay.record(cmd, index as usize, o.pixels_per_point, o.primitives);
                });
            }
            frame.release(id, Access::Present);
        })?;
        Ok(overlay_result?)
    }
}
