//! How a pass touches a resource, in the style of vk-sync: each [`Access`] maps to the
//! pipeline stages, access mask and image layout it needs, and the frame graph turns pairs of
//! accesses into barriers.
use ash::vk;

#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Access {
    /// Nothing yet (contents undefined).
    Nothing,
    /// Written (and blended/loaded) as a colour attachment.
    ColorAttachment,
    /// Depth test and write.
    DepthAttachment,
    /// Depth test only (read-only depth attachment).
    DepthAttachmentRead,
    /// Sampled in a fragment shader.
    FragmentSampled,
    /// Sampled (vertex texture fetch) in a vertex shader: caustic splatting.
    VertexSampled,
    /// Sampled in a compute shader.
    ComputeSampled,
    /// Read as a storage image/buffer in a compute shader.
    ComputeRead,
    /// Written (or read and written) as a storage image/buffer in a compute shader.
    ComputeWrite,
    /// Read as a storage buffer in a vertex shader.
    VertexStorageRead,
    /// Written (or read and written) as a storage image/buffer in a vertex shader
    /// (`vertexPipelineStoresAndAtomics`).
    VertexStorageWrite,
    /// Read as a storage buffer in a fragment shader.
    FragmentStorageRead,
    /// Written (or read and written, atomics) as a storage buffer in a fragment shader.
    FragmentStorageWrite,
    /// Indirect draw/dispatch arguments (HistoPyramid output counts).
    IndirectArgs,
    /// The scene's vertices as every pass reads them: vertex attributes, and storage reads
    /// in any shader stage.
    VertexData,
    /// Source of a copy.
    TransferRead,
    /// Destination of a copy or clear.
    TransferWrite,
    /// Read by the host after the submission's fence.
    HostRead,
    /// Handed to the presentation engine (a swapchain image after its last pass). The
    /// queue-present semaphore orders it; the barrier only changes the layout.
    Present,
}

/// What an access means to Vulkan.
#[derive(Clone, Copy, Debug)]
pub struct AccessInfo {
    pub stages: vk::PipelineStageFlags,
    pub access: vk::AccessFlags,
    pub layout: vk::ImageLayout,
    pub writes: bool,
}

impl Access {
    pub fn info(self, depth_format: bool) -> AccessInfo {
        use vk::AccessFlags as A;
        use vk::ImageLayout as L;
        use vk::PipelineStageFlags as S;
        let sampled = if depth_format { L::DEPTH_STENCIL_READ_ONLY_OPTIMAL } else { L::SHADER_READ_ONLY_OPTIMAL };
        let (stages, access, layout, writes) = match self {
            Access::Nothing => (S::TOP_OF_PIPE, A::empty(), L::UNDEFINED, false),
            Access::ColorAttachment => (
                S::COLOR_ATTACHMENT_OUTPUT,
                A::COLOR_ATTACHMENT_READ | A::COLOR_ATTACHMENT_WRITE,
                L::COLOR_ATTACHMENT_OPTIMAL,
                true,
            ),
            Access::DepthAttachment => (
                S::EARLY_FRAGMENT_TESTS | S::LATE_FRAGMENT_TESTS,
                A::DEPTH_STENCIL_ATTACHMENT_READ | A::DEPTH_STENCIL_ATTACHMENT_WRITE,
                L::DEPTH_STENCIL_ATTACHMENT_OPTIMAL,
                true,
            ),
            Access::DepthAttachmentRead => (
                S::EARLY_FRAGMENT_TESTS | S::LATE_FRAGMENT_TESTS,
                A::DEPTH_STENCIL_ATTACHMENT_READ,
                L::DEPTH_STENCIL_READ_ONLY_OPTIMAL,
                // The attachment's store op counts as a write for synchronization.
                true,
            ),
            Access::FragmentSampled => (S::FRAGMENT_SHADER, A::SHADER_READ, sampled, false),
            Access::VertexSampled => (S::VERTEX_SHADER, A::SHADER_READ, sampled, false),
            Access::ComputeSampled => (S::COMPUTE_SHADER, A::SHADER_READ, sampled, false),
            Access::ComputeRead => (S::COMPUTE_SHADER, A::SHADER_READ, L::GENERAL, false),
            Access::ComputeWrite => (S::COMPUTE_SHADER, A::SHADER_READ | A::SHADER_WRITE, L::GENERAL, true),
            Access::VertexStorageRead => (S::VERTEX_SHADER, A::SHADER_READ, L::GENERAL, false),
            Access::VertexStorageWrite => (S::VERTEX_SHADER, A::SHADER_READ | A::SHADER_WRITE, L::GENERAL, true),
            Access::FragmentStorageRead => (S::FRAGMENT_SHADER, A::SHADER_READ, L::GENERAL, false),
            Access::FragmentStorageWrite => (S::FRAGMENT_SHADER, A::SHADER_READ | A::SHADER_WRITE, L::GENERAL, true),
            Access::IndirectArgs => (S::DRAW_INDIRECT, A::INDIRECT_COMMAND_READ, L::UNDEFINED, false),
            Access::VertexData => (
                S::VERTEX_INPUT | S::VERTEX_SHADER | S::FRAGMENT_SHADER | S::COMPUTE_SHADER,
                A::VERTEX_ATTRIBUTE_READ | A::SHADER_READ,
                L::UNDEFINED,
                false,
            ),
            Access::TransferRead => (S::TRANSFER, A::TRANSFER_READ, L::TRANSFER_SRC_OPTIMAL, false),
            Access::TransferWrite => (S::TRANSFER, A::TRANSFER_WRITE, L::TRANSFER_DST_OPTIMAL, true),
            Access::HostRead => (S::HOST, A::HOST_READ, L::GENERAL, false),
            Access::Present => (S::BOTTOM_OF_PIPE, A::empty(), L::PRESENT_SRC_KHR, false),
        };
        AccessInfo { stages, access, layout, writes }
    }
}

/// A resolved image barrier, emitted by [`crate::gpu::Cmd::barriers`].
#[derive(Clone, Copy, Debug)]
pub struct ImageBarrier {
    pub image: vk::Image,
    pub aspect: vk::ImageAspectFlags,
    pub layers: u32,
    pub src_stages: vk::PipelineStageFlags,
    pub src_access: vk::AccessFlags,
    pub dst_stages: vk::PipelineStageFlags,
    pub dst_access: vk::AccessFlags,
    pub old_layout: vk::ImageLayout,
    pub new_layout: vk::ImageLayout,
}

/// A resolved buffer (memory) barrier.
#[derive(Clone, Copy, Debug)]
pub struct BufferBarrier {
    pub buffer: vk::Buffer,
    pub src_stages: vk::PipelineStageFlags,
    pub src_access: vk::AccessFlags,
    pub dst_stages: vk::PipelineStageFlags,
    pub dst_access: vk::AccessFlags,
}
