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

use super::frame::TimedFrame;
use super::{FrameTiming, Pixels, RenderError};
use crate::shaders;
use crate::vk::{
    Buffer, BufferUsage, Context, CullModeFlags, Format, Framebuffer, GraphicsPipeline,
    GraphicsPipelineDesc, Image, ImageAspectFlags, ImageDesc, ImageUsageFlags, PipelineLayout,
    RenderPass, ShaderModule,
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
    frame: TimedFrame,
    readback: Buffer,
    _pipeline: GraphicsPipeline,
    _layout: PipelineLayout,
    _framebuffer: Framebuffer,
    _render_pass: RenderPass,
    _target: Image,
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
        let target = Image::new(
            ctx,
            "empty pass target",
            ImageDesc {
                width,
                height,
                format: FORMAT,
                usage: ImageUsageFlags::COLOR_ATTACHMENT | ImageUsageFlags::TRANSFER_SRC,
                mip_levels: 1,
                aspect: ImageAspectFlags::COLOR,
            },
        )?;
        let render_pass = RenderPass::single_color(ctx, FORMAT)?;
        let framebuffer = Framebuffer::single(ctx, &render_pass, &target)?;
        let layout = PipelineLayout::new(ctx, &[])?;
        let vertex = ShaderModule::new(ctx, shaders::FULLSCREEN_VERT)?;
        let fragment = ShaderModule::new(ctx, shaders::CONSTANT_FRAG)?;
        let pipeline = GraphicsPipeline::new(
            ctx,
            &layout,
            &render_pass,
            &GraphicsPipelineDesc {
                vertex_shader: &vertex,
                fragment_shader: &fragment,
                specialization: &[],
                vertex_stride: 0,
                vertex_attributes: &[],
                cull_mode: CullModeFlags::NONE,
                // There is no depth attachment; depth state is ignored.
                depth_test: false,
                depth_write: false,
                alpha_blend: false,
                subpass: 0,
            },
        )?;
        let readback = Buffer::new(
            ctx,
            "empty pass readback",
            width as u64 * height as u64 * 4,
            BufferUsage::Readback,
        )?;
        // Recorded like the scene renderer's frame: one timestamp on each
        // side of the render pass.
        let frame = TimedFrame::begin(ctx, 1)?;
        let cmd = frame.cmd();
        // The load op is DONT_CARE (the triangle covers every pixel), so no
        // clear value is given: one would be ignored, and best-practices
        // validation warns about it.
        cmd.begin_render_pass(&render_pass, &framebuffer, &[]);
        cmd.bind_pipeline(&pipeline);
        cmd.draw(3);
        cmd.end_render_pass();
        frame.stamp();
        cmd.copy_image_to_buffer(&target, &readback);
        let frame = frame.finish()?;

        Ok(EmptyPass {
            frame,
            readback,
            _pipeline: pipeline,
            _layout: layout,
            _framebuffer: framebuffer,
            _render_pass: render_pass,
            _target: target,
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

impl Drop for EmptyPass {
    fn drop(&mut self) {
        // As for the renderer: nothing may be pending when resources go.
        let _ = self.ctx.wait_idle();
    }
}
