//! The only module that touches `ash` directly.
//!
//! Small RAII wrappers over Vulkan objects. Each holds an `Arc<Context>` so
//! the device outlives it, and destroys its handle in `Drop`. Every `unsafe`
//! block states the invariant it relies on.

mod buffer;
// Test-only deliberate mistakes; see the `deliberate-misuse` feature.
mod commands;
mod context;
#[cfg(feature = "deliberate-misuse")]
mod deliberate_misuse;
mod descriptors;
mod image;
mod pipeline;
mod pipeline_cache;
mod query;
mod render_graph;
mod swapchain;
pub mod validation;

pub use ash::vk::{
    AccessFlags, CompareOp, CullModeFlags, DescriptorType, Format, ImageAspectFlags, ImageLayout,
    ImageUsageFlags, PipelineStageFlags, ShaderStageFlags,
};
pub use buffer::{Buffer, BufferUsage};
pub use commands::{CommandBuffer, Fence, ImageUse};
pub use context::{Context, ContextOptions, DeviceInfo};
pub use descriptors::{DescriptorBinding, DescriptorPool, DescriptorSet, DescriptorSetLayout};
pub use image::{bytes_per_texel, Image, ImageDesc, MipView, Sampler, SamplerFilter};
pub use pipeline::{
    Blend, ComputePipeline, GraphicsPipeline, GraphicsPipelineDesc, PipelineLayout, ShaderModule,
    VertexAttribute,
};
pub use pipeline_cache::{PipelineCacheStore, PIPELINE_CACHE_ENV};
pub use query::{PipelineStats, PipelineStatsQueries, TimestampQueries};
pub use render_graph::{
    AttachmentSpec, AttachmentStart, DepthUse, FrameTargets, Framebuffer, RenderPass,
    RenderTargets, RunSpec, SubpassSpec,
};
pub use swapchain::{PresentMode, Presented, Surface, Swapchain, WindowHandles};

/// Errors from the Vulkan layer.
#[derive(Debug, thiserror::Error)]
pub enum VkError {
    #[error(
        "could not load the Vulkan loader (is libvulkan1 installed? run scripts/setup.sh): {0}"
    )]
    Loader(String),
    #[error("VK_LAYER_KHRONOS_validation is not installed (package vulkan-validationlayers; run scripts/setup.sh)")]
    MissingValidationLayer,
    #[error("no Vulkan 1.2 device matches '{wanted}' (give an index or part of a name); available: {}", if available.is_empty() { "none".to_string() } else { available.join(", ") })]
    NoDevice {
        wanted: String,
        available: Vec<String>,
    },
    #[error("the device has no graphics queue")]
    NoGraphicsQueue,
    #[error("format {format:?} does not support {what} on this device")]
    UnsupportedFormat {
        format: ash::vk::Format,
        what: String,
    },
    #[error("{name} image {width}x{height} is outside this device's limit of {max_width}x{max_height} ({limit})")]
    ImageSize {
        name: String,
        width: u32,
        height: u32,
        max_width: u32,
        max_height: u32,
        limit: &'static str,
    },
    #[error("Vulkan call failed: {0}")]
    Api(#[from] ash::vk::Result),
    #[error("memory allocation failed: {0}")]
    Allocation(#[from] gpu_allocator::AllocationError),
    #[error("frame description: {0}")]
    Graph(String),
    #[error("invalid SPIR-V: {0}")]
    Spirv(String),
    #[error("window surface: {0}")]
    Surface(String),
    #[error("unsupported: {0}")]
    Unsupported(String),
}

pub use image::{supports_linear_blits, supports_linear_sampling};

/// A colour clear value.
pub fn clear_color(rgba: [f32; 4]) -> ash::vk::ClearValue {
    ash::vk::ClearValue {
        color: ash::vk::ClearColorValue { float32: rgba },
    }
}

/// A depth clear value (stencil 0).
pub fn clear_depth(depth: f32) -> ash::vk::ClearValue {
    ash::vk::ClearValue {
        depth_stencil: ash::vk::ClearDepthStencilValue { depth, stencil: 0 },
    }
}
