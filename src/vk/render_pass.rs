//! The renderer's render pass and its framebuffer, plus a single-colour
//! pass for measuring the driver's floor.
//!
//! The scene pass has two subpasses: subpass 0 draws the scene into a float
//! HDR colour attachment with reversed-Z float depth; subpass 1 reads the HDR
//! colour as an input attachment and writes the tone-mapped 8-bit sRGB
//! output. The HDR image is only stored to memory when someone asked for it
//! (`keep_hdr`); otherwise its contents die with the pass.

use super::{Context, Image, VkError};
use ash::vk;
use std::sync::Arc;

/// The formats and choices the render pass is built from.
#[derive(Clone, Copy, Debug)]
pub struct RenderPassDesc {
    pub hdr_format: vk::Format,
    pub depth_format: vk::Format,
    pub output_format: vk::Format,
    /// Store the HDR attachment and leave it in TRANSFER_SRC_OPTIMAL for
    /// readback.
    pub keep_hdr: bool,
    /// Load the HDR attachment (copied in before the pass, in
    /// COLOR_ATTACHMENT_OPTIMAL) instead of clearing it: tone-mapping an
    /// existing HDR image.
    pub load_hdr: bool,
}

pub const HDR_ATTACHMENT: u32 = 0;
pub const DEPTH_ATTACHMENT: u32 = 1;
pub const OUTPUT_ATTACHMENT: u32 = 2;

pub struct RenderPass {
    ctx: Arc<Context>,
    pub(crate) handle: vk::RenderPass,
}

impl RenderPass {
    pub fn new(ctx: &Arc<Context>, desc: RenderPassDesc) -> Result<RenderPass, VkError> {
        let attachment = |format, load, store, final_layout| {
            vk::AttachmentDescription::default()
                .format(format)
                .samples(vk::SampleCountFlags::TYPE_1)
                .load_op(load)
                .store_op(store)
                .stencil_load_op(vk::AttachmentLoadOp::DONT_CARE)
                .stencil_store_op(vk::AttachmentStoreOp::DONT_CARE)
                .initial_layout(vk::ImageLayout::UNDEFINED)
                .final_layout(final_layout)
        };
        let (hdr_load, hdr_initial) = if desc.load_hdr {
            (
                vk::AttachmentLoadOp::LOAD,
                vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL,
            )
        } else {
            (vk::AttachmentLoadOp::CLEAR, vk::ImageLayout::UNDEFINED)
        };
        let (hdr_store, hdr_final) = if desc.keep_hdr {
            (
                vk::AttachmentStoreOp::STORE,
                vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
            )
        } else {
            (
                vk::AttachmentStoreOp::DONT_CARE,
                vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL,
            )
        };
        let attachments = [
            attachment(desc.hdr_format, hdr_load, hdr_store, hdr_final).initial_layout(hdr_initial),
            attachment(
                desc.depth_format,
                vk::AttachmentLoadOp::CLEAR,
                vk::AttachmentStoreOp::DONT_CARE,
                vk::ImageLayout::DEPTH_STENCIL_ATTACHMENT_OPTIMAL,
            ),
            // The tone-map pass writes every pixel, so nothing is loaded.
            attachment(
                desc.output_format,
                vk::AttachmentLoadOp::DONT_CARE,
                vk::AttachmentStoreOp::STORE,
                vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
            ),
        ];
        let scene_colour = [vk::AttachmentReference {
            attachment: HDR_ATTACHMENT,
            layout: vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL,
        }];
        let scene_depth = vk::AttachmentReference {
            attachment: DEPTH_ATTACHMENT,
            layout: vk::ImageLayout::DEPTH_STENCIL_ATTACHMENT_OPTIMAL,
        };
        let tonemap_input = [vk::AttachmentReference {
            attachment: HDR_ATTACHMENT,
            layout: vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL,
        }];
        let tonemap_output = [vk::AttachmentReference {
            attachment: OUTPUT_ATTACHMENT,
            layout: vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL,
        }];
        let subpasses = [
            vk::SubpassDescription::default()
                .pipeline_bind_point(vk::PipelineBindPoint::GRAPHICS)
                .color_attachments(&scene_colour)
                .depth_stencil_attachment(&scene_depth),
            vk::SubpassDescription::default()
                .pipeline_bind_point(vk::PipelineBindPoint::GRAPHICS)
                .input_attachments(&tonemap_input)
                .color_attachments(&tonemap_output),
        ];
        let attachment_stages = vk::PipelineStageFlags::COLOR_ATTACHMENT_OUTPUT
            | vk::PipelineStageFlags::EARLY_FRAGMENT_TESTS
            | vk::PipelineStageFlags::LATE_FRAGMENT_TESTS;
        let attachment_writes = vk::AccessFlags::COLOR_ATTACHMENT_WRITE
            | vk::AccessFlags::DEPTH_STENCIL_ATTACHMENT_WRITE;
        let dependencies = [
            // The previous submission of this frame (same attachments) must
            // finish writing, reading in the tone-map pass and copying out
            // before this one overwrites the attachments.
            vk::SubpassDependency::default()
                .src_subpass(vk::SUBPASS_EXTERNAL)
                .dst_subpass(0)
                .src_stage_mask(
                    attachment_stages
                        | vk::PipelineStageFlags::FRAGMENT_SHADER
                        | vk::PipelineStageFlags::TRANSFER,
                )
                .src_access_mask(attachment_writes)
                .dst_stage_mask(attachment_stages)
                .dst_access_mask(
                    attachment_writes
                        | vk::AccessFlags::COLOR_ATTACHMENT_READ
                        | vk::AccessFlags::DEPTH_STENCIL_ATTACHMENT_READ,
                ),
            // Scene colour written in subpass 0 is read per pixel in subpass 1.
            vk::SubpassDependency::default()
                .src_subpass(0)
                .dst_subpass(1)
                .src_stage_mask(vk::PipelineStageFlags::COLOR_ATTACHMENT_OUTPUT)
                .src_access_mask(vk::AccessFlags::COLOR_ATTACHMENT_WRITE)
                .dst_stage_mask(vk::PipelineStageFlags::FRAGMENT_SHADER)
                .dst_access_mask(vk::AccessFlags::INPUT_ATTACHMENT_READ)
                .dependency_flags(vk::DependencyFlags::BY_REGION),
            // The output (and the kept HDR image) are copied out afterwards.
            vk::SubpassDependency::default()
                .src_subpass(1)
                .dst_subpass(vk::SUBPASS_EXTERNAL)
                .src_stage_mask(vk::PipelineStageFlags::COLOR_ATTACHMENT_OUTPUT)
                .src_access_mask(vk::AccessFlags::COLOR_ATTACHMENT_WRITE)
                .dst_stage_mask(vk::PipelineStageFlags::TRANSFER)
                .dst_access_mask(vk::AccessFlags::TRANSFER_READ),
        ];
        let info = vk::RenderPassCreateInfo::default()
            .attachments(&attachments)
            .subpasses(&subpasses)
            .dependencies(&dependencies);
        // SAFETY: valid device; all referenced arrays are locals.
        let handle = unsafe { ctx.device.create_render_pass(&info, None) }?;
        Ok(RenderPass {
            ctx: ctx.clone(),
            handle,
        })
    }

    /// One subpass writing one colour attachment of `format`, every pixel
    /// (so nothing is loaded), stored and left in TRANSFER_SRC_OPTIMAL for
    /// readback. This is the least a frame can do, used to measure the
    /// driver's floor.
    pub fn single_color(ctx: &Arc<Context>, format: vk::Format) -> Result<RenderPass, VkError> {
        let attachments = [vk::AttachmentDescription::default()
            .format(format)
            .samples(vk::SampleCountFlags::TYPE_1)
            .load_op(vk::AttachmentLoadOp::DONT_CARE)
            .store_op(vk::AttachmentStoreOp::STORE)
            .stencil_load_op(vk::AttachmentLoadOp::DONT_CARE)
            .stencil_store_op(vk::AttachmentStoreOp::DONT_CARE)
            .initial_layout(vk::ImageLayout::UNDEFINED)
            .final_layout(vk::ImageLayout::TRANSFER_SRC_OPTIMAL)];
        let colour = [vk::AttachmentReference {
            attachment: 0,
            layout: vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL,
        }];
        let subpasses = [vk::SubpassDescription::default()
            .pipeline_bind_point(vk::PipelineBindPoint::GRAPHICS)
            .color_attachments(&colour)];
        let dependencies = [
            // The previous submission's writes and its copy out must be done
            // before this one writes the attachment again.
            vk::SubpassDependency::default()
                .src_subpass(vk::SUBPASS_EXTERNAL)
                .dst_subpass(0)
                .src_stage_mask(
                    vk::PipelineStageFlags::COLOR_ATTACHMENT_OUTPUT
                        | vk::PipelineStageFlags::TRANSFER,
                )
                .src_access_mask(vk::AccessFlags::COLOR_ATTACHMENT_WRITE)
                .dst_stage_mask(vk::PipelineStageFlags::COLOR_ATTACHMENT_OUTPUT)
                .dst_access_mask(vk::AccessFlags::COLOR_ATTACHMENT_WRITE),
            // The attachment is copied out afterwards.
            vk::SubpassDependency::default()
                .src_subpass(0)
                .dst_subpass(vk::SUBPASS_EXTERNAL)
                .src_stage_mask(vk::PipelineStageFlags::COLOR_ATTACHMENT_OUTPUT)
                .src_access_mask(vk::AccessFlags::COLOR_ATTACHMENT_WRITE)
                .dst_stage_mask(vk::PipelineStageFlags::TRANSFER)
                .dst_access_mask(vk::AccessFlags::TRANSFER_READ),
        ];
        let info = vk::RenderPassCreateInfo::default()
            .attachments(&attachments)
            .subpasses(&subpasses)
            .dependencies(&dependencies);
        // SAFETY: valid device; all referenced arrays are locals.
        let handle = unsafe { ctx.device.create_render_pass(&info, None) }?;
        Ok(RenderPass {
            ctx: ctx.clone(),
            handle,
        })
    }
}

impl Drop for RenderPass {
    fn drop(&mut self) {
        // SAFETY: pipelines/framebuffers using it are gone or idle.
        unsafe { self.ctx.device.destroy_render_pass(self.handle, None) };
    }
}

/// The attachments of one [`RenderPass`], bound together.
pub struct Framebuffer {
    ctx: Arc<Context>,
    pub(crate) handle: vk::Framebuffer,
    pub(crate) extent: vk::Extent2D,
}

impl Framebuffer {
    /// `attachments` in the order HDR, depth, output.
    pub fn new(
        ctx: &Arc<Context>,
        pass: &RenderPass,
        attachments: [&Image; 3],
    ) -> Result<Framebuffer, VkError> {
        let extent = vk::Extent2D {
            width: attachments[0].desc.width,
            height: attachments[0].desc.height,
        };
        Framebuffer::create(ctx, pass, &attachments.map(|i| i.view), extent)
    }

    /// The framebuffer of a [`RenderPass::single_color`] pass.
    pub fn single(
        ctx: &Arc<Context>,
        pass: &RenderPass,
        attachment: &Image,
    ) -> Result<Framebuffer, VkError> {
        let extent = vk::Extent2D {
            width: attachment.desc.width,
            height: attachment.desc.height,
        };
        Framebuffer::create(ctx, pass, &[attachment.view], extent)
    }

    fn create(
        ctx: &Arc<Context>,
        pass: &RenderPass,
        views: &[vk::ImageView],
        extent: vk::Extent2D,
    ) -> Result<Framebuffer, VkError> {
        let info = vk::FramebufferCreateInfo::default()
            .render_pass(pass.handle)
            .attachments(views)
            .width(extent.width)
            .height(extent.height)
            .layers(1);
        // SAFETY: views match the pass's attachment formats and sizes.
        let handle = unsafe { ctx.device.create_framebuffer(&info, None) }?;
        Ok(Framebuffer {
            ctx: ctx.clone(),
            handle,
            extent,
        })
    }
}

impl Drop for Framebuffer {
    fn drop(&mut self) {
        // SAFETY: no pending command buffer uses it.
        unsafe { self.ctx.device.destroy_framebuffer(self.handle, None) };
    }
}
