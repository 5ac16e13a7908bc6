//! `aerial view`: the scene in a window, flown through with the keyboard
//! and mouse, with live knobs and per-pass GPU times.
//!
//! The window shows exactly what `aerial render` computes: the same
//! [`Renderer`](crate::render::Renderer), frame plan and passes, drawn at
//! the window's size and copied into the window's swapchain image after
//! each frame. Data still flows one way: input changes the viewer's copy
//! of the scene (camera, sun, knobs, size), the scene is planned and
//! drawn, and the image goes to the window and, on request, to files.
//!
//! - `camera`: the fly-through camera and its speed rule;
//! - `input`: keys and what they do; `script`: input from a file;
//! - `knobs`: which knobs the number keys cycle;
//! - `timing`: per-pass medians over the last frames;
//! - `window`: the event loop that ties them to the window and GPU.

pub mod camera;
pub mod input;
pub mod knobs;
pub mod script;
pub mod timing;
mod window;

use crate::render::RenderError;
use crate::scene::{KnobError, Scene};
use crate::vk::validation::{Validation, ValidationFailed, ValidationMessage};
use crate::vk::{PresentMode, VkError};
pub use script::{Script, ScriptAction, ScriptError};

/// The time step of a scripted frame, in seconds: frames of a script are
/// this far apart in the simulation however long they take to draw.
pub const SCRIPT_STEP_SECONDS: f64 = 1.0 / 60.0;

/// What to show and how.
pub struct ViewOptions {
    /// The scene; its output size is the window's initial inner size.
    pub scene: Scene,
    /// How the scene is named in the title and screenshots' metadata.
    pub scene_name: String,
    pub validate: Validation,
    pub device: Option<String>,
    /// Where the device's pipeline cache is kept between runs; every
    /// rebuild of the renderer (a knob cycled) goes through it too.
    pub pipeline_cache: crate::vk::PipelineCacheStore,
    pub present_mode: PresentMode,
    /// Input to replay instead of (as well as) a person's.
    pub script: Option<Script>,
}

/// Why the viewer stopped with an error.
#[derive(Debug, thiserror::Error)]
pub enum ViewerError {
    #[error("cannot open a window: {0} (is DISPLAY or WAYLAND_DISPLAY set?)")]
    Window(String),
    #[error(transparent)]
    Render(#[from] RenderError),
    #[error(transparent)]
    Image(#[from] crate::image_io::ImageError),
    #[error(transparent)]
    Vulkan(#[from] VkError),
    #[error(transparent)]
    Knob(#[from] KnobError),
    #[error("screenshot {path}: {reason}")]
    Screenshot { path: String, reason: String },
    #[error("no screenshot written: {0}")]
    Validation(#[from] ValidationFailed),
}

/// How a viewer session ended.
pub struct ViewOutcome {
    /// Frames drawn.
    pub frames: u64,
    /// The error that stopped it, if any.
    pub error: Option<ViewerError>,
    /// Validation messages, read after the device was destroyed (empty
    /// without validation).
    pub validation: Vec<ValidationMessage>,
    /// Per-pass and per-step times over the last frames, as `T` prints.
    pub timings: String,
}

/// Opens the window and runs until it is closed, `Esc`, or a script's
/// `quit`.
pub fn run(options: ViewOptions) -> ViewOutcome {
    window::run(options)
}
