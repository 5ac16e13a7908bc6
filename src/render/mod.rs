//! The frame: the scene's meshes built once (`geometry`), the frame as data
//! (`plan`: attachments and passes), one type per pass (`passes`), the GPU
//! resources and the recorded command buffer (`renderer`); the images are
//! written by `crate::image_io`. `tiles` culls lights per screen tile for deferred
//! lighting, and `static_lights` carries unchanging lights as
//! specialization constants; `octahedral` is the G-buffer's normal encoding. `empty_pass`
//! is the driver's floor that benchmarks divide by; `cpu_renderer` draws the
//! exact CPU image that sweeps can measure against; `timed_submit` submits
//! the recorded frame and times it.

pub mod cpu_renderer;
pub mod draw_list;
pub mod empty_pass;
pub mod geometry;
mod gpu_types;
pub mod octahedral;
pub mod passes;
pub mod plan;
pub mod preflight;
pub mod prepass_rule;
mod renderer;
mod scene_resources;
pub mod shadow_resources;
pub mod shadow_view;
pub mod sky_resources;
mod static_lights;
mod sun_tables;
pub mod tiles;
mod timed_submit;

/// The images a renderer reads back are `image_io`'s, so they are written
/// as they are.
pub use crate::image_io::Pixels;
pub use cpu_renderer::{render_on_cpu, render_on_cpu_with, CpuRenderError, Transport};
pub use empty_pass::EmptyPass;
pub use geometry::SceneGeometry;
pub use passes::{PassType, PASSES};
pub use plan::{subpass_timing_note, FramePlan};
pub use renderer::{FrameTiming, Renderer, ViewChange};
pub use timed_submit::PrefixFrames;

use std::path::PathBuf;

#[derive(Debug, thiserror::Error)]
pub enum RenderError {
    #[error(transparent)]
    Vulkan(#[from] crate::vk::VkError),
    #[error("texture {path}: {reason}")]
    Texture { path: PathBuf, reason: String },
    #[error("{what} is reached by {lights} lights; this device's uniform blocks hold at most {max} (raise light_cutoff to leave out faint ones)")]
    TooManyLights {
        what: String,
        lights: usize,
        max: usize,
    },
    /// The plan and its passes disagree (a pass reads an attachment the
    /// plan does not declare, and the like): a defect, reported rather
    /// than a panic.
    #[error("frame description: {0}")]
    Frame(String),
    #[error("invalid HDR input image: {0}")]
    InvalidImage(String),
    #[error(transparent)]
    File(#[from] crate::safe_files::FileError),
    #[error(transparent)]
    Image(#[from] crate::image_io::ImageError),
    #[error(transparent)]
    Budget(#[from] crate::budget::BudgetError),
    #[error("{object}: {reason}")]
    Object { object: String, reason: String },
    #[error("size {width}x{height}: each side must be in 1..={max}", max = crate::scene::MAX_OUTPUT_SIZE)]
    Size { width: u32, height: u32 },
    #[error(transparent)]
    Count(#[from] crate::callgrind::CountError),
    /// Stopped at a safe point by an interrupt (see [`crate::interrupt`]).
    #[error(transparent)]
    Interrupted(#[from] crate::interrupt::Interrupted),
}
