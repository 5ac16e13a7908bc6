//! Command pool + command buffer recording, submission and fences.
//!
//! The renderer records a frame once and submits it as often as it is asked
//! to; `CommandBuffer` owns its own pool, so its lifetime is simple.

use super::descriptors::DescriptorSet;
use super::image::ImageState;
use super::{
    Buffer, ComputePipeline, Context, GraphicsPipeline, Image, PipelineLayout,
    PipelineStatsQueries, RenderTargets, TimestampQueries, VkError,
};
use ash::vk;
use std::sync::Arc;

/// Every stage at which the renderer reads or writes images.
const IMAGE_STAGES: vk::PipelineStageFlags = vk::PipelineStageFlags::from_raw(
    vk::PipelineStageFlags::COLOR_ATTACHMENT_OUTPUT.as_raw()
        | vk::PipelineStageFlags::EARLY_FRAGMENT_TESTS.as_raw()
        | vk::PipelineStageFlags::LATE_FRAGMENT_TESTS.as_raw()
        | vk::PipelineStageFlags::FRAGMENT_SHADER.as_raw()
        | vk::PipelineStageFlags::TRANSFER.as_raw(),
);

/// A fence, for waiting on a submission.
pub struct Fence {
    ctx: Arc<Context>,
    handle: vk::Fence,
}

impl Fence {
    pub fn new(ctx: &Arc<Context>) -> Result<Fence, VkError> {
        // SAFETY: valid device.
        let handle = unsafe {
            ctx.device
                .create_fence(&vk::FenceCreateInfo::default(), None)
        }?;
        Ok(Fence {
            ctx: ctx.clone(),
            handle,
        })
    }

    /// Waits for the fence and resets it for the next submission.
    pub fn wait_and_reset(&self) -> Result<(), VkError> {
        // SAFETY: the fence belongs to this device and was submitted.
        unsafe {
            self.ctx
                .device
                .wait_for_fences(&[self.handle], true, u64::MAX)?;
            self.ctx.device.reset_fences(&[self.handle])?;
        }
        Ok(())
    }
}

impl Drop for Fence {
    fn drop(&mut self) {
        // SAFETY: callers wait on the fence before dropping it; a wait here
        // would hide that bug, so we only destroy.
        unsafe { self.ctx.device.destroy_fence(self.handle, None) };
    }
}

/// A primary command buffer with its own pool.
pub struct CommandBuffer {
    ctx: Arc<Context>,
    pool: vk::CommandPool,
    pub(crate) handle: vk::CommandBuffer,
}

/// What the next command does with an image; `CommandBuffer::transition`
/// derives the layout and the barrier from it and the image's state.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ImageUse {
    TransferSrc,
    TransferDst,
    /// Sampled by fragment shaders.
    FragmentSampled,
    /// Sampled by fragment and compute shaders (tables both read).
    ShaderSampled,
    /// Written as a storage image by compute shaders.
    ComputeWrite,
    /// Sampled by compute shaders only (an attachment a compute pass
    /// between render passes reads).
    ComputeSampled,
    /// Written as a colour attachment (e.g. loaded by a render pass).
    ColourAttachment,
    /// Read as an input attachment (loaded by a render pass whose first
    /// use of it is a read).
    InputAttachment,
}

impl ImageUse {
    fn layout_stage_access(self) -> (vk::ImageLayout, vk::PipelineStageFlags, vk::AccessFlags) {
        match self {
            ImageUse::TransferSrc => (
                vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
                vk::PipelineStageFlags::TRANSFER,
                vk::AccessFlags::TRANSFER_READ,
            ),
            ImageUse::TransferDst => (
                vk::ImageLayout::TRANSFER_DST_OPTIMAL,
                vk::PipelineStageFlags::TRANSFER,
                vk::AccessFlags::TRANSFER_WRITE,
            ),
            ImageUse::FragmentSampled => (
                vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL,
                vk::PipelineStageFlags::FRAGMENT_SHADER,
                vk::AccessFlags::SHADER_READ,
            ),
            ImageUse::ShaderSampled => (
                vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL,
                vk::PipelineStageFlags::FRAGMENT_SHADER | vk::PipelineStageFlags::COMPUTE_SHADER,
                vk::AccessFlags::SHADER_READ,
            ),
            ImageUse::ComputeSampled => (
                vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL,
                vk::PipelineStageFlags::COMPUTE_SHADER,
                vk::AccessFlags::SHADER_READ,
            ),
            ImageUse::ComputeWrite => (
                vk::ImageLayout::GENERAL,
                vk::PipelineStageFlags::COMPUTE_SHADER,
                vk::AccessFlags::SHADER_WRITE,
            ),
            ImageUse::ColourAttachment => (
                vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL,
                vk::PipelineStageFlags::COLOR_ATTACHMENT_OUTPUT,
                vk::AccessFlags::COLOR_ATTACHMENT_READ | vk::AccessFlags::COLOR_ATTACHMENT_WRITE,
            ),
            ImageUse::InputAttachment => (
                vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL,
                vk::PipelineStageFlags::FRAGMENT_SHADER,
                vk::AccessFlags::INPUT_ATTACHMENT_READ,
            ),
        }
    }

    fn writes(self) -> bool {
        matches!(
            self,
            ImageUse::TransferDst | ImageUse::ColourAttachment | ImageUse::ComputeWrite
        )
    }
}

/// One image layout transition or memory dependency on some mip levels.
#[derive(Clone, Copy, Debug)]
struct ImageBarrier {
    pub old_layout: vk::ImageLayout,
    pub new_layout: vk::ImageLayout,
    pub src_stage: vk::PipelineStageFlags,
    pub src_access: vk::AccessFlags,
    pub dst_stage: vk::PipelineStageFlags,
    pub dst_access: vk::AccessFlags,
    pub base_mip: u32,
    pub mip_count: u32,
}

impl CommandBuffer {
    pub fn new(ctx: &Arc<Context>) -> Result<CommandBuffer, VkError> {
        let info = vk::CommandPoolCreateInfo::default().queue_family_index(ctx.queue_family);
        // SAFETY: valid device and queue family.
        let pool = unsafe { ctx.device.create_command_pool(&info, None) }?;
        let alloc = vk::CommandBufferAllocateInfo::default()
            .command_pool(pool)
            .level(vk::CommandBufferLevel::PRIMARY)
            .command_buffer_count(1);
        // SAFETY: the pool was just created.
        let handle = match unsafe { ctx.device.allocate_command_buffers(&alloc) } {
            Ok(b) => b[0],
            Err(e) => {
                // SAFETY: nothing allocated from the pool.
                unsafe { ctx.device.destroy_command_pool(pool, None) };
                return Err(e.into());
            }
        };
        Ok(CommandBuffer {
            ctx: ctx.clone(),
            pool,
            handle,
        })
    }

    pub fn begin(&self) -> Result<(), VkError> {
        // SAFETY: the buffer is not pending (callers wait on their fence).
        unsafe {
            self.ctx
                .device
                .begin_command_buffer(self.handle, &vk::CommandBufferBeginInfo::default())
        }?;
        Ok(())
    }

    pub fn end(&self) -> Result<(), VkError> {
        // SAFETY: recording was begun.
        unsafe { self.ctx.device.end_command_buffer(self.handle) }?;
        Ok(())
    }

    /// Submits the recorded buffer and signals `fence`.
    pub fn submit(&self, fence: &Fence) -> Result<(), VkError> {
        let buffers = [self.handle];
        let submit = vk::SubmitInfo::default().command_buffers(&buffers);
        // SAFETY: the buffer is fully recorded; the fence is unsignalled.
        unsafe {
            self.ctx
                .device
                .queue_submit(self.ctx.queue, &[submit], fence.handle)
        }?;
        Ok(())
    }

    /// Records with `f`, submits, and waits: for uploads done at load time.
    pub fn run_once(ctx: &Arc<Context>, f: impl FnOnce(&CommandBuffer)) -> Result<(), VkError> {
        let cmd = CommandBuffer::new(ctx)?;
        let fence = Fence::new(ctx)?;
        cmd.begin()?;
        f(&cmd);
        cmd.end()?;
        cmd.submit(&fence)?;
        fence.wait_and_reset()
    }

    /// Makes `image` ready for `next`: the one place barriers outside render
    /// passes come from. The barrier waits for the image's last recorded use
    /// and moves it to the layout `next` needs; none is recorded when the
    /// image is already in that layout, nothing wrote it since, and `next`
    /// only reads.
    pub fn transition(&self, image: &Image, next: ImageUse) {
        let state = image.state.get();
        let (layout, stage, access) = next.layout_stage_access();
        let needed = state.layout != layout || !state.pending_writes.is_empty() || next.writes();
        if needed {
            self.image_barrier(
                image,
                ImageBarrier {
                    old_layout: state.layout,
                    new_layout: layout,
                    src_stage: state.stage,
                    src_access: state.pending_writes,
                    dst_stage: stage,
                    dst_access: access,
                    base_mip: 0,
                    mip_count: image.desc.mip_levels,
                },
            );
        }
        self.set_state(image, next);
    }

    /// Like [`transition`](Self::transition), but the current contents are
    /// not needed (they are about to be overwritten). In a frame that is
    /// recorded once and submitted many times, the previous submission's
    /// use of the image is not known at record time, so this waits for
    /// every stage that can touch an image (attachment output, depth
    /// tests, fragment shading, transfers) and their writes.
    pub fn transition_discarding(&self, image: &Image, next: ImageUse) {
        let (layout, stage, access) = next.layout_stage_access();
        self.image_barrier(
            image,
            ImageBarrier {
                old_layout: vk::ImageLayout::UNDEFINED,
                new_layout: layout,
                src_stage: IMAGE_STAGES,
                src_access: vk::AccessFlags::COLOR_ATTACHMENT_WRITE
                    | vk::AccessFlags::DEPTH_STENCIL_ATTACHMENT_WRITE
                    | vk::AccessFlags::TRANSFER_WRITE,
                dst_stage: stage,
                dst_access: access,
                base_mip: 0,
                mip_count: image.desc.mip_levels,
            },
        );
        self.set_state(image, next);
    }

    fn set_state(&self, image: &Image, now: ImageUse) {
        let (layout, stage, access) = now.layout_stage_access();
        image.state.set(ImageState {
            layout,
            stage,
            pending_writes: if now.writes() {
                access
                    & (vk::AccessFlags::TRANSFER_WRITE
                        | vk::AccessFlags::COLOR_ATTACHMENT_WRITE
                        | vk::AccessFlags::SHADER_WRITE)
            } else {
                vk::AccessFlags::empty()
            },
        });
    }

    fn image_barrier(&self, image: &Image, b: ImageBarrier) {
        let mut range = image.full_range();
        range.base_mip_level = b.base_mip;
        range.level_count = b.mip_count;
        let barrier = vk::ImageMemoryBarrier::default()
            .old_layout(b.old_layout)
            .new_layout(b.new_layout)
            .src_access_mask(b.src_access)
            .dst_access_mask(b.dst_access)
            .src_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
            .dst_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
            .image(image.handle)
            .subresource_range(range);
        // SAFETY: recording; the image is alive until the submission ends.
        unsafe {
            self.ctx.device.cmd_pipeline_barrier(
                self.handle,
                b.src_stage,
                b.dst_stage,
                vk::DependencyFlags::empty(),
                &[],
                &[],
                &[barrier],
            )
        };
    }

    /// Makes a compute shader's write of mip `level` visible to the next
    /// compute dispatches, which read it (sampled or as a storage image)
    /// or write it again, the image staying in GENERAL layout: the barrier
    /// between the levels of a chain that compute shaders build one level
    /// per dispatch. The image must already be in GENERAL layout for
    /// compute writes (`transition*(image, ImageUse::ComputeWrite)`); its
    /// tracked state stays that, so a later `transition` waits for the
    /// last level's write too.
    pub fn compute_level_barrier(&self, image: &Image, level: u32) {
        debug_assert_eq!(image.state.get().layout, vk::ImageLayout::GENERAL);
        self.image_barrier(
            image,
            ImageBarrier {
                old_layout: vk::ImageLayout::GENERAL,
                new_layout: vk::ImageLayout::GENERAL,
                src_stage: vk::PipelineStageFlags::COMPUTE_SHADER,
                src_access: vk::AccessFlags::SHADER_WRITE,
                dst_stage: vk::PipelineStageFlags::COMPUTE_SHADER,
                dst_access: vk::AccessFlags::SHADER_READ | vk::AccessFlags::SHADER_WRITE,
                base_mip: level,
                mip_count: 1,
            },
        );
    }

    /// Copies mip level 0 of a colour image into a buffer, tightly packed
    /// (moving the image to TRANSFER_SRC_OPTIMAL first if needed).
    pub fn copy_image_to_buffer(&self, image: &Image, buffer: &Buffer) {
        self.transition(image, ImageUse::TransferSrc);
        let region = vk::BufferImageCopy::default()
            .image_subresource(vk::ImageSubresourceLayers {
                aspect_mask: vk::ImageAspectFlags::COLOR,
                mip_level: 0,
                base_array_layer: 0,
                layer_count: 1,
            })
            .image_extent(vk::Extent3D {
                width: image.desc.width,
                height: image.desc.height,
                depth: 1,
            });
        // SAFETY: recording; buffer is large enough (callers size it from
        // the image) and the image is in TRANSFER_SRC_OPTIMAL.
        unsafe {
            self.ctx.device.cmd_copy_image_to_buffer(
                self.handle,
                image.handle,
                vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
                buffer.handle,
                &[region],
            )
        };
    }

    /// Copies a tightly packed buffer into mip level 0 of an image, whose
    /// earlier contents are discarded.
    pub fn copy_buffer_to_image(&self, buffer: &Buffer, image: &Image) {
        self.transition_discarding(image, ImageUse::TransferDst);
        let region = vk::BufferImageCopy::default()
            .image_subresource(vk::ImageSubresourceLayers {
                aspect_mask: vk::ImageAspectFlags::COLOR,
                mip_level: 0,
                base_array_layer: 0,
                layer_count: 1,
            })
            .image_extent(vk::Extent3D {
                width: image.desc.width,
                height: image.desc.height,
                depth: 1,
            });
        // SAFETY: recording; the buffer holds width*height texels.
        unsafe {
            self.ctx.device.cmd_copy_buffer_to_image(
                self.handle,
                buffer.handle,
                image.handle,
                vk::ImageLayout::TRANSFER_DST_OPTIMAL,
                &[region],
            )
        };
    }

    /// Fills every mip level below 0 by successive linear blits from level
    /// 0 (just written by a copy, every level in TRANSFER_DST_OPTIMAL); on
    /// return every level is ready for fragment-shader sampling.
    pub fn generate_mipmaps(&self, image: &Image) {
        let (mut w, mut h) = (image.desc.width as i32, image.desc.height as i32);
        let levels = image.desc.mip_levels;
        for level in 1..levels {
            // Previous level: written (copy or blit) → blit source.
            self.image_barrier(
                image,
                ImageBarrier {
                    old_layout: vk::ImageLayout::TRANSFER_DST_OPTIMAL,
                    new_layout: vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
                    src_stage: vk::PipelineStageFlags::TRANSFER,
                    src_access: vk::AccessFlags::TRANSFER_WRITE,
                    dst_stage: vk::PipelineStageFlags::TRANSFER,
                    dst_access: vk::AccessFlags::TRANSFER_READ,
                    base_mip: level - 1,
                    mip_count: 1,
                },
            );
            let (nw, nh) = ((w / 2).max(1), (h / 2).max(1));
            let layers = |mip| vk::ImageSubresourceLayers {
                aspect_mask: vk::ImageAspectFlags::COLOR,
                mip_level: mip,
                base_array_layer: 0,
                layer_count: 1,
            };
            let blit = vk::ImageBlit::default()
                .src_subresource(layers(level - 1))
                .src_offsets([vk::Offset3D::default(), vk::Offset3D { x: w, y: h, z: 1 }])
                .dst_subresource(layers(level))
                .dst_offsets([vk::Offset3D::default(), vk::Offset3D { x: nw, y: nh, z: 1 }]);
            // SAFETY: recording; level-1 is TRANSFER_SRC, level is TRANSFER_DST
            // (the whole image was put there before the upload).
            unsafe {
                self.ctx.device.cmd_blit_image(
                    self.handle,
                    image.handle,
                    vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
                    image.handle,
                    vk::ImageLayout::TRANSFER_DST_OPTIMAL,
                    &[blit],
                    vk::Filter::LINEAR,
                )
            };
            self.image_barrier(
                image,
                ImageBarrier {
                    old_layout: vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
                    new_layout: vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL,
                    src_stage: vk::PipelineStageFlags::TRANSFER,
                    src_access: vk::AccessFlags::TRANSFER_READ,
                    dst_stage: vk::PipelineStageFlags::FRAGMENT_SHADER,
                    dst_access: vk::AccessFlags::SHADER_READ,
                    base_mip: level - 1,
                    mip_count: 1,
                },
            );
            (w, h) = (nw, nh);
        }
        self.image_barrier(
            image,
            ImageBarrier {
                old_layout: vk::ImageLayout::TRANSFER_DST_OPTIMAL,
                new_layout: vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL,
                src_stage: vk::PipelineStageFlags::TRANSFER,
                src_access: vk::AccessFlags::TRANSFER_WRITE,
                dst_stage: vk::PipelineStageFlags::FRAGMENT_SHADER,
                dst_access: vk::AccessFlags::SHADER_READ,
                base_mip: levels - 1,
                mip_count: 1,
            },
        );
        image.state.set(ImageState {
            layout: vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL,
            stage: vk::PipelineStageFlags::FRAGMENT_SHADER,
            pending_writes: vk::AccessFlags::empty(),
        });
    }

    /// Begins `pass` (with a viewport and scissor over the whole
    /// framebuffer). A loaded attachment is first moved to the layout its
    /// first subpass uses, after whatever wrote it.
    /// `images` are the frame's attachments, which `pass.attachments`
    /// index.
    pub fn begin_render_pass(&self, pass: &RenderTargets, images: &[Image]) {
        // What the subpasses sample, written by earlier render passes.
        for &a in &pass.sampled {
            self.transition(&images[a], ImageUse::FragmentSampled);
        }
        for (&a, initial) in pass.attachments.iter().zip(&pass.initial_layouts) {
            let image = &images[a];
            match *initial {
                vk::ImageLayout::UNDEFINED => {}
                vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL => {
                    self.transition(image, ImageUse::ColourAttachment)
                }
                // A loaded attachment first read as an input attachment.
                _ => self.transition(image, ImageUse::InputAttachment),
            }
        }
        let extent = pass.framebuffer.extent;
        let info = vk::RenderPassBeginInfo::default()
            .render_pass(pass.render_pass.handle)
            .framebuffer(pass.framebuffer.handle)
            .render_area(vk::Rect2D {
                offset: vk::Offset2D::default(),
                extent,
            })
            .clear_values(&pass.clears);
        // SAFETY: recording outside a render pass; the framebuffer was made
        // for this pass, with one clear value per attachment.
        unsafe {
            self.ctx
                .device
                .cmd_begin_render_pass(self.handle, &info, vk::SubpassContents::INLINE)
        };
        self.set_viewport(0, 0, extent.width, extent.height);
    }

    /// Draws into the `width`×`height` rectangle at (`x`, `y`) of the
    /// framebuffer (viewport and scissor both), depth range 0..1.
    pub fn set_viewport(&self, x: u32, y: u32, width: u32, height: u32) {
        let viewport = vk::Viewport {
            x: x as f32,
            y: y as f32,
            width: width as f32,
            height: height as f32,
            min_depth: 0.0,
            max_depth: 1.0,
        };
        let scissor = vk::Rect2D {
            offset: vk::Offset2D {
                x: x as i32,
                y: y as i32,
            },
            extent: vk::Extent2D { width, height },
        };
        // SAFETY: every pipeline declares viewport and scissor dynamic.
        unsafe {
            self.ctx
                .device
                .cmd_set_viewport(self.handle, 0, &[viewport]);
            self.ctx.device.cmd_set_scissor(self.handle, 0, &[scissor]);
        }
    }

    pub fn next_subpass(&self) {
        // SAFETY: inside a render pass with a following subpass.
        unsafe {
            self.ctx
                .device
                .cmd_next_subpass(self.handle, vk::SubpassContents::INLINE)
        };
    }

    /// Ends `pass`; its attachments are then in their final layouts. A
    /// stored attachment's writes were made visible to transfer reads by
    /// the pass's own outgoing dependency.
    pub fn end_render_pass(&self, pass: &RenderTargets, images: &[Image]) {
        // SAFETY: inside the last subpass of this render pass.
        unsafe { self.ctx.device.cmd_end_render_pass(self.handle) };
        for (&a, layout) in pass.attachments.iter().zip(&pass.final_layouts) {
            let image = &images[a];
            let state = if *layout == vk::ImageLayout::TRANSFER_SRC_OPTIMAL {
                ImageState {
                    layout: *layout,
                    stage: vk::PipelineStageFlags::TRANSFER,
                    pending_writes: vk::AccessFlags::empty(),
                }
            } else {
                // The writes a later barrier must wait for: those the
                // attachment's last layout allows (naming others trips the
                // best-practices check on that barrier).
                let pending_writes = match *layout {
                    vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL => {
                        vk::AccessFlags::COLOR_ATTACHMENT_WRITE
                    }
                    vk::ImageLayout::DEPTH_STENCIL_ATTACHMENT_OPTIMAL => {
                        vk::AccessFlags::DEPTH_STENCIL_ATTACHMENT_WRITE
                    }
                    _ => vk::AccessFlags::empty(),
                };
                ImageState {
                    layout: *layout,
                    stage: IMAGE_STAGES,
                    pending_writes,
                }
            };
            image.state.set(state);
        }
    }

    pub fn bind_pipeline(&self, pipeline: &GraphicsPipeline) {
        // SAFETY: recording; the pipeline lives until the submission ends.
        unsafe {
            self.ctx.device.cmd_bind_pipeline(
                self.handle,
                vk::PipelineBindPoint::GRAPHICS,
                pipeline.handle,
            )
        };
    }

    pub fn bind_descriptor_set(
        &self,
        layout: &PipelineLayout,
        index: u32,
        set: &DescriptorSet,
        dynamic_offsets: &[u32],
    ) {
        self.bind_set(
            vk::PipelineBindPoint::GRAPHICS,
            layout,
            index,
            set,
            dynamic_offsets,
        );
    }

    pub fn bind_compute_pipeline(&self, pipeline: &ComputePipeline) {
        // SAFETY: recording; the pipeline lives until the submission ends.
        unsafe {
            self.ctx.device.cmd_bind_pipeline(
                self.handle,
                vk::PipelineBindPoint::COMPUTE,
                pipeline.handle,
            )
        };
    }

    pub fn bind_compute_descriptor_set(
        &self,
        layout: &PipelineLayout,
        index: u32,
        set: &DescriptorSet,
    ) {
        self.bind_set(vk::PipelineBindPoint::COMPUTE, layout, index, set, &[]);
    }

    fn bind_set(
        &self,
        point: vk::PipelineBindPoint,
        layout: &PipelineLayout,
        index: u32,
        set: &DescriptorSet,
        dynamic_offsets: &[u32],
    ) {
        // SAFETY: recording; the set matches the layout at `index`.
        unsafe {
            self.ctx.device.cmd_bind_descriptor_sets(
                self.handle,
                point,
                layout.handle,
                index,
                &[set.handle],
                dynamic_offsets,
            )
        };
    }

    /// Runs the bound compute pipeline over `groups` workgroups.
    pub fn dispatch(&self, groups: [u32; 3]) {
        // SAFETY: recording outside a render pass with a compute pipeline
        // and its descriptor sets bound.
        unsafe {
            self.ctx
                .device
                .cmd_dispatch(self.handle, groups[0], groups[1], groups[2])
        };
    }

    pub fn bind_geometry(&self, buffer: &Buffer, vertex_offset: u64, index_offset: u64) {
        // SAFETY: recording; the buffer holds both vertex and index data at
        // these offsets.
        unsafe {
            self.ctx.device.cmd_bind_vertex_buffers(
                self.handle,
                0,
                &[buffer.handle],
                &[vertex_offset],
            );
            self.ctx.device.cmd_bind_index_buffer(
                self.handle,
                buffer.handle,
                index_offset,
                vk::IndexType::UINT32,
            );
        }
    }

    pub fn bind_vertex_buffer(&self, buffer: &Buffer, offset: u64) {
        // SAFETY: recording; the buffer holds vertex data from `offset`.
        unsafe {
            self.ctx
                .device
                .cmd_bind_vertex_buffers(self.handle, 0, &[buffer.handle], &[offset])
        };
    }

    /// Binds `buffer` from `offset` as the per-instance vertex data
    /// ([`INSTANCE_BINDING`](super::pipeline::INSTANCE_BINDING)).
    pub fn bind_instances(&self, buffer: &Buffer, offset: u64) {
        // SAFETY: recording; the buffer holds per-instance vertex data from
        // `offset`.
        unsafe {
            self.ctx.device.cmd_bind_vertex_buffers(
                self.handle,
                super::pipeline::INSTANCE_BINDING,
                &[buffer.handle],
                &[offset],
            )
        };
    }

    /// `instance_count` instances of the bound indexed geometry, reading
    /// per-instance data from slot `first_instance` on.
    pub fn draw_indexed_instances(
        &self,
        index_count: u32,
        instance_count: u32,
        first_instance: u32,
    ) {
        // SAFETY: recording inside a render pass with pipeline, geometry
        // and instance data bound; the instance buffer holds the slots.
        unsafe {
            self.ctx.device.cmd_draw_indexed(
                self.handle,
                index_count,
                instance_count,
                0,
                0,
                first_instance,
            )
        };
    }

    pub fn draw_indexed(&self, index_count: u32) {
        // SAFETY: recording inside a render pass with pipeline and geometry bound.
        unsafe {
            self.ctx
                .device
                .cmd_draw_indexed(self.handle, index_count, 1, 0, 0, 0)
        };
    }

    pub fn draw(&self, vertex_count: u32) {
        // SAFETY: recording inside a render pass with a pipeline bound.
        unsafe { self.ctx.device.cmd_draw(self.handle, vertex_count, 1, 0, 0) };
    }

    /// A global memory dependency: the accesses `src_access` in `src_stage`
    /// (e.g. a compute shader's write to a buffer) happen before, and are
    /// visible to, `dst_access` in `dst_stage`; with empty accesses it only
    /// orders execution (a write after the previous submission's reads).
    pub fn memory_barrier(
        &self,
        src_stage: vk::PipelineStageFlags,
        src_access: vk::AccessFlags,
        dst_stage: vk::PipelineStageFlags,
        dst_access: vk::AccessFlags,
    ) {
        let barrier = vk::MemoryBarrier::default()
            .src_access_mask(src_access)
            .dst_access_mask(dst_access);
        // SAFETY: recording outside a render pass.
        unsafe {
            self.ctx.device.cmd_pipeline_barrier(
                self.handle,
                src_stage,
                dst_stage,
                vk::DependencyFlags::empty(),
                &[barrier],
                &[],
                &[],
            )
        };
    }

    pub fn reset_queries(&self, queries: &TimestampQueries) {
        // SAFETY: recording outside a render pass.
        unsafe {
            self.ctx
                .device
                .cmd_reset_query_pool(self.handle, queries.pool, 0, queries.capacity)
        };
    }

    /// Resets every pipeline-statistics query of `queries`.
    pub fn reset_stats_queries(&self, queries: &PipelineStatsQueries) {
        // SAFETY: recording outside a render pass.
        unsafe {
            for pool in [queries.pool, queries.occlusion] {
                self.ctx
                    .device
                    .cmd_reset_query_pool(self.handle, pool, 0, queries.capacity)
            }
        };
    }

    /// Begins counting pipeline statistics into query `index`.
    pub fn begin_stats_query(&self, queries: &PipelineStatsQueries, index: u32) {
        // SAFETY: recording; index < capacity, reset in this buffer and not
        // active; the caller ends it in the same subpass.
        unsafe {
            self.ctx.device.cmd_begin_query(
                self.handle,
                queries.pool,
                index,
                vk::QueryControlFlags::empty(),
            );
            self.ctx.device.cmd_begin_query(
                self.handle,
                queries.occlusion,
                index,
                if self.ctx.occlusion_precise() {
                    vk::QueryControlFlags::PRECISE
                } else {
                    vk::QueryControlFlags::empty()
                },
            );
        };
    }

    /// Ends query `index`, begun by [`Self::begin_stats_query`].
    pub fn end_stats_query(&self, queries: &PipelineStatsQueries, index: u32) {
        // SAFETY: recording; the query is active and was begun in this
        // subpass (or outside any render pass, as now).
        unsafe {
            self.ctx
                .device
                .cmd_end_query(self.handle, queries.occlusion, index);
            self.ctx
                .device
                .cmd_end_query(self.handle, queries.pool, index);
        };
    }

    /// Writes timestamp `index` once all earlier work has finished.
    pub fn write_timestamp(&self, queries: &TimestampQueries, index: u32) {
        // SAFETY: recording; index < capacity and was reset in this buffer.
        unsafe {
            self.ctx.device.cmd_write_timestamp(
                self.handle,
                vk::PipelineStageFlags::BOTTOM_OF_PIPE,
                queries.pool,
                index,
            )
        };
    }
}

impl Drop for CommandBuffer {
    fn drop(&mut self) {
        // SAFETY: owners wait for submissions before dropping; destroying the
        // pool frees its command buffer.
        unsafe { self.ctx.device.destroy_command_pool(self.pool, None) };
    }
}
