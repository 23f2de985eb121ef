use ash::vk;

/// Errors of the gpu layer. Each names the Vulkan call or resource that failed so that a
/// message from the CLI is enough to find the spot.
#[derive(Debug, thiserror::Error)]
pub enum GpuError {
    #[error(
        "cannot load the Vulkan loader (libvulkan.so.1): {0}. Install it with \
         `apt-get install libvulkan1 mesa-vulkan-drivers` (lavapipe runs on the CPU)"
    )]
    NoLoader(String),
    #[error(
        "no Vulkan driver found ({call} returned {result:?}). Install one, e.g. \
         `apt-get install mesa-vulkan-drivers` for lavapipe, or point VK_DRIVER_FILES at its ICD json"
    )]
    NoDriver { call: &'static str, result: vk::Result },
    #[error("no Vulkan device matches {0:?}; available: {1}")]
    NoSuchDevice(String, String),
    #[error("no Vulkan device with a graphics+compute queue was found")]
    NoSuitableDevice,
    #[error("{call} failed: {result:?}")]
    Vk { call: &'static str, result: vk::Result },
    #[error("GPU memory allocation for {name} failed: {source}")]
    Alloc { name: String, source: gpu_allocator::AllocationError },
    #[error("shader {0} is not embedded in this binary (is it under glsl/?)")]
    MissingShader(String),
    #[error("shader {0} is not valid SPIR-V: {1}")]
    InvalidShader(String, String),
    #[error("{0}")]
    Unsupported(String),
    /// A pipeline's named specialisation constants do not fit its shaders.
    #[error("specialisation of {0}")]
    Specialization(String),
    #[error("the window surface was lost (VK_ERROR_SURFACE_LOST_KHR)")]
    SurfaceLost,
    #[error("overlay (egui) renderer: {0}")]
    Overlay(String),
    /// A fence wait ran past its limit: the GPU is hung or far slower than any supported one.
    #[error("waiting for {what} timed out after {seconds} s (the GPU is hung or far too slow)")]
    Timeout { what: &'static str, seconds: u64 },
}

pub type GpuResult<T> = Result<T, GpuError>;

/// Attach the name of the failing call to a raw `vk::Result`.
pub(crate) trait VkContext<T> {
    fn vk(self, call: &'static str) -> GpuResult<T>;
}

impl<T> VkContext<T> for Result<T, vk::Result> {
    fn vk(self, call: &'static str) -> GpuResult<T> {
        self.map_err(|result| GpuError::Vk { call, result })
    }
}
