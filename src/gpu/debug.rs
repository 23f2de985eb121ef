//! Debug-utils messenger (counting validation errors per instance) and labels.
use std::ffi::{c_void, CStr};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, Mutex};

use ash::vk;

use super::error::{GpuResult, VkContext};

/// Per-instance counters written by the debug callback.
#[derive(Default)]
pub(crate) struct DebugState {
    pub errors: AtomicU64,
    pub warnings: AtomicU64,
    pub messages: Mutex<Vec<String>>,
}

/// A context's validation counters, readable after the context is gone: the layer reports
/// leaked objects while the device and instance are destroyed, after every other check.
#[derive(Clone)]
pub struct ValidationLog(pub(crate) Arc<DebugState>);

impl ValidationLog {
    /// Validation-layer errors reported so far on this instance.
    pub fn errors(&self) -> u64 {
        self.0.errors.load(Ordering::Relaxed)
    }

    /// Validation-layer warnings reported so far on this instance.
    pub fn warnings(&self) -> u64 {
        self.0.warnings.load(Ordering::Relaxed)
    }

    /// The text of every validation error so far (for test failure messages).
    pub fn messages(&self) -> Vec<String> {
        self.0.messages.lock().unwrap().clone()
    }
}

pub(crate) struct Messenger {
    loader: ash::ext::debug_utils::Instance,
    handle: vk::DebugUtilsMessengerEXT,
    // Keeps the state alive for as long as the callback may be called.
    _state: Arc<DebugState>,
}

impl Messenger {
    pub fn new(entry: &ash::Entry, instance: &ash::Instance, state: &Arc<DebugState>) -> GpuResult<Self> {
        let loader = ash::ext::debug_utils::Instance::new(entry, instance);
        let info = messenger_create_info(state);
        // SAFETY: the user-data pointer stays valid: `_state` keeps the Arc alive until destroy.
        let handle =
            unsafe { loader.create_debug_utils_messenger(&info, None) }.vk("vkCreateDebugUtilsMessengerEXT")?;
        Ok(Messenger { loader, handle, _state: state.clone() })
    }

    /// # Safety
    /// Must be called before the instance is destroyed.
    pub unsafe fn destroy(self) {
        // SAFETY: guaranteed by the caller.
        unsafe { self.loader.destroy_debug_utils_messenger(self.handle, None) };
    }
}

pub(crate) fn messenger_create_info(state: &Arc<DebugState>) -> vk::DebugUtilsMessengerCreateInfoEXT<'static> {
    vk::DebugUtilsMessengerCreateInfoEXT::default()
        .message_severity(vk::DebugUtilsMessageSeverityFlagsEXT::ERROR | vk::DebugUtilsMessageSeverityFlagsEXT::WARNING)
        .message_type(
            vk::DebugUtilsMessageTypeFlagsEXT::GENERAL
                | vk::DebugUtilsMessageTypeFlagsEXT::VALIDATION
                | vk::DebugUtilsMessageTypeFlagsEXT::PERFORMANCE,
        )
        .pfn_user_callback(Some(callback))
        .user_data(Arc::as_ptr(state) as *mut c_void)
}

/// Never panics (a panic cannot unwind through the C caller): it only counts and prints.
unsafe extern "system" fn callback(
    severity: vk::DebugUtilsMessageSeverityFlagsEXT,
    kind: vk::DebugUtilsMessageTypeFlagsEXT,
    data: *const vk::DebugUtilsMessengerCallbackDataEXT<'_>,
    user: *mut c_void,
) -> vk::Bool32 {
    let _ = std::panic::catch_unwind(|| {
        // SAFETY: the layer passes valid callback data; user points at a live DebugState.
        let (message, state) = unsafe {
            let msg = if data.is_null() || (*data).p_message.is_null() {
                "(no message)".to_string()
            } else {
                CStr::from_ptr((*data).p_message).to_string_lossy().into_owned()
            };
            (msg, (user as *const DebugState).as_ref())
        };
        let Some(state) = state else { return };
        if severity.contains(vk::DebugUtilsMessageSeverityFlagsEXT::ERROR) {
            state.errors.fetch_add(1, Ordering::Relaxed);
            if let Ok(mut m) = state.messages.lock() {
                m.push(message.clone());
            }
            eprintln!("[vulkan {kind:?} error] {message}");
        } else if kind.contains(vk::DebugUtilsMessageTypeFlagsEXT::VALIDATION) {
            state.warnings.fetch_add(1, Ordering::Relaxed);
            if std::env::var_os("PRISM_VK_WARNINGS").is_some() {
                eprintln!("[vulkan warning] {message}");
            }
        }
    });
    vk::FALSE
}
