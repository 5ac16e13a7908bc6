//! The empty pass: the floor of what one pass costs on this driver.
//!
//! One render pass with a single RGBA8 colour attachment and one full-screen
//! triangle whose fragment shader writes a constant (`glsl/constant.frag`).
//! It is timed with GPU timestamps exactly as the scene renderer times its
//! passes (one interval from before the render pass begins to after it
//! ends), so a scene pass's time divided by this one says how many "empty
//! full-screen passes" of work it is. On a CPU driver such as lavapipe that
//! floor is far from zero: every pixel is still shaded and stored.
//!
//! The attachment is copied to a host buffer after the timed interval so
//! tests can check that the pass really wrote every pixel.

use super::timed_submit::TimedCommands;
use super::{FrameTiming, Pixels, RenderError};
use crate::shaders;
use crate::vk::{
    AttachmentSpec, AttachmentStart, Buffer, BufferUsage, Context, Format, FrameTargets,
    GraphicsPipeline, PipelineLayout, SubpassSpec,
};
use std::sync::Arc;

/// The attachment format: plain 8-bit RGBA, the cheapest colour target.
const FORMAT: Format = Format::R8G8B8A8_UNORM;

/// The name of the one timed pass.
pub const PASS_NAME: &str = "empty";

/// What `glsl/constant.frag` writes, as stored in the UNORM attachment
/// (each channel may round either way by one).
pub const CONSTANT_RGBA8: [u8; 4] = [64, 128, 191, 255];

/// The empty pass's GPU objects and its recorded command buffer. Fields
/// drop in declaration order: command buffer first, context last.
pub struct EmptyPass {
    frame: TimedCommands,
    /// The same frame without the draw, recorded on first use by
    /// `PrefixFrames::render_prefix`.
    without_draw: Option<TimedCommands>,
    readback: Buffer,
    pipeline: GraphicsPipeline,
    _layout: PipelineLayout,
    render_pass: FrameTargets,
    width: u32,
    height: u32,
    ctx: Arc<Context>,
}

impl EmptyPass {
    /// Builds the pass at `width` x `height` and records its frame once.
    pub fn new(ctx: &Arc<Context>, width: u32, height: u32) -> Result<EmptyPass, RenderError> {
        // Scenes are checked when loaded; this pass takes its size directly,
        // and a zero-sized image would be invalid Vulkan usage.
        let valid = 1..=crate::scene::MAX_OUTPUT_SIZE;
        if !valid.contains(&width) || !valid.contains(&height) {
            return Err(RenderError::Size { width, height });
        }
        // One attachment, written at every pixel (nothing loaded) and read
        // back after the pass; built by the same render-graph builder as
        // scene frames.
        let render_pass = FrameTargets::single(
            ctx,
            width,
            height,
            &[AttachmentSpec {
                name: "empty pass target",
                format: FORMAT,
                start: AttachmentStart::Undefined,
                read_after: true,
                kept_after: false,
                compute: false,
            }],
            &[SubpassSpec {
                name: PASS_NAME,
                colour: vec![0],
                ..SubpassSpec::default()
            }],
        )?;
        let layout = PipelineLayout::new(ctx, &[])?;
        let pipeline = super::passes::fullscreen_pipeline(
            ctx,
            &layout,
            &render_pass.runs[0].render_pass,
            0,
            shaders::CONSTANT_FRAG.base(),
            &[],
            None,
        )?;
        let readback = Buffer::new(
            ctx,
            "empty pass readback",
            width as u64 * height as u64 * 4,
            BufferUsage::Readback,
        )?;
        // Recorded like the scene renderer's frame: one timestamp on each
        // side of the render pass.
        let frame = record(ctx, &render_pass, &pipeline, &readback, true)?;

        Ok(EmptyPass {
            frame,
            without_draw: None,
            readback,
            pipeline,
            _layout: layout,
            render_pass,
            width,
            height,
            ctx: ctx.clone(),
        })
    }

    /// Submits the recorded pass and waits for it. `pass_ms` has one entry
    /// (empty when the device has no timestamps); `cpu_ms` is submit to
    /// fence, as for scene frames.
    pub fn render_frame(&mut self) -> Result<FrameTiming, RenderError> {
        self.frame.submit()
    }

    /// The attachment as the last frame left it.
    pub fn output(&self) -> Pixels<u8> {
        Pixels {
            width: self.width,
            height: self.height,
            data: self.readback.read().to_vec(),
        }
    }
}

impl super::PrefixFrames for EmptyPass {
    fn pass_count(&self) -> usize {
        1
    }

    /// Like `Renderer::render_prefix` for this one-pass frame: 0 submits
    /// the frame without its draw (the render pass begun and ended, the
    /// copy out), 1 the whole frame.
    fn render_prefix(&mut self, recorded: usize) -> Result<FrameTiming, RenderError> {
        if recorded >= 1 {
            return self.frame.submit();
        }
        if self.without_draw.is_none() {
            self.without_draw = Some(record(
                &self.ctx,
                &self.render_pass,
                &self.pipeline,
                &self.readback,
                false,
            )?);
        }
        self.without_draw.as_mut().expect("recorded above").submit()
    }
}

impl Drop for EmptyPass {
    fn drop(&mut self) {
        // As for the renderer: nothing may be pending when resources go.
        let _ = self.ctx.wait_idle();
    }
}

/// The empty pass's frame: the render pass with one full-screen draw (or,
/// without `draw`, none), timed, then copied out.
fn record(
    ctx: &Arc<Context>,
    render_pass: &FrameTargets,
    pipeline: &GraphicsPipeline,
    readback: &Buffer,
    draw: bool,
) -> Result<TimedCommands, RenderError> {
    let frame = TimedCommands::begin(ctx, 1)?;
    let cmd = frame.cmd();
    cmd.begin_render_pass(&render_pass.runs[0], &render_pass.images);
    frame.begin_pass();
    if draw {
        cmd.bind_pipeline(pipeline);
        cmd.draw(3);
    }
    frame.end_pass();
    cmd.end_render_pass(&render_pass.runs[0], &render_pass.images);
    frame.stamp();
    cmd.copy_image_to_buffer(&render_pass.images[0], readback);
    frame.finish()
}
