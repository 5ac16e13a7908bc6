//! Presenting to a window: the Vulkan surface of a window, and a swapchain
//! whose images each frame receive a copy of the renderer's output.
//!
//! The renderer is unchanged by presentation: it draws into its own
//! attachments and reads the output back as it does headless. Presenting
//! is one more small submission per frame: wait for the acquired image,
//! copy (or, when the channel order differs, blit) the output attachment
//! into it, and hand it to the presentation engine.

use super::{Context, Image, VkError};
use ash::vk;
use raw_window_handle::{HasDisplayHandle, HasWindowHandle};
use std::sync::Arc;

/// How presented images are queued (`VkPresentModeKHR`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum PresentMode {
    /// Wait for vertical blank; never tears (the only mode every device has).
    Fifo,
    /// Replace the queued image; no tearing, no waiting.
    Mailbox,
    /// Present at once; may tear.
    Immediate,
}

impl PresentMode {
    fn vk(self) -> vk::PresentModeKHR {
        match self {
            PresentMode::Fifo => vk::PresentModeKHR::FIFO,
            PresentMode::Mailbox => vk::PresentModeKHR::MAILBOX,
            PresentMode::Immediate => vk::PresentModeKHR::IMMEDIATE,
        }
    }
}

/// What happened to a frame handed to [`Swapchain::present`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Presented {
    /// Shown.
    Done,
    /// Shown, but the swapchain no longer matches the window exactly:
    /// create a new one when convenient.
    Suboptimal,
    /// Not shown: the window changed (resized) and the swapchain must be
    /// created again before the next frame.
    OutOfDate,
}

/// The Vulkan surface of a window. It keeps the window alive, since the
/// surface must not outlive it.
pub struct Surface {
    /// The instance must outlive the surface.
    _ctx: Arc<Context>,
    loader: ash::khr::surface::Instance,
    handle: vk::SurfaceKHR,
    _window: Arc<dyn WindowHandles>,
}

/// A window with the raw handles a surface is made from.
pub trait WindowHandles: HasWindowHandle + HasDisplayHandle + Send + Sync {}
impl<T: HasWindowHandle + HasDisplayHandle + Send + Sync> WindowHandles for T {}

impl Surface {
    /// The surface of `window`, on a context created with the window's
    /// display (`ContextOptions::display`); fails if the context's queue
    /// cannot present to it.
    pub fn new(ctx: &Arc<Context>, window: Arc<dyn WindowHandles>) -> Result<Surface, VkError> {
        let err = |e: raw_window_handle::HandleError| VkError::Surface(e.to_string());
        let display = window.display_handle().map_err(err)?.as_raw();
        let raw_window = window.window_handle().map_err(err)?.as_raw();
        // SAFETY: the instance was created with the extensions this display
        // needs (Context::new with `display`), and the window the handles
        // belong to is kept alive by the surface (`_window`), which is
        // destroyed before the instance (it holds the context).
        let handle = unsafe {
            ash_window::create_surface(&ctx.entry, &ctx.instance, display, raw_window, None)
        }?;
        let loader = ash::khr::surface::Instance::new(&ctx.entry, &ctx.instance);
        let surface = Surface {
            _ctx: ctx.clone(),
            loader,
            handle,
            _window: window,
        };
        // SAFETY: valid physical device, queue family and surface.
        let supported = unsafe {
            surface.loader.get_physical_device_surface_support(
                ctx.physical_device,
                ctx.queue_family,
                handle,
            )
        }?;
        if !supported {
            return Err(VkError::Surface(format!(
                "the device's graphics queue cannot present to this window ({})",
                ctx.device_info().name
            )));
        }
        Ok(surface)
    }
}

impl Drop for Surface {
    fn drop(&mut self) {
        // SAFETY: every swapchain of this surface holds an Arc to it, so
        // none is left.
        unsafe { self.loader.destroy_surface(self.handle, None) };
    }
}

/// A swapchain and what one presented frame needs: a semaphore for the
/// acquired image, one per image for the finished copy (a present may
/// still wait on the one of an image until that image is acquired again),
/// a fence, and a command pool re-recorded each frame (the source image
/// may be a new one after every rebuild of the renderer).
pub struct Swapchain {
    ctx: Arc<Context>,
    surface: Arc<Surface>,
    loader: ash::khr::swapchain::Device,
    handle: vk::SwapchainKHR,
    images: Vec<vk::Image>,
    format: vk::Format,
    /// Copy when the swapchain's channel order matches the output's, blit
    /// (which converts) otherwise.
    blit: bool,
    width: u32,
    height: u32,
    acquired: vk::Semaphore,
    copied: Vec<vk::Semaphore>,
    fence: vk::Fence,
    pool: vk::CommandPool,
    cmd: vk::CommandBuffer,
}

/// The output's format (`render::plan::OUTPUT_FORMAT`): 8-bit RGBA
/// holding sRGB-encoded values.
const SOURCE_FORMAT: vk::Format = vk::Format::R8G8B8A8_UNORM;

/// The swapchain's format, and whether the output is blitted into it
/// (rather than copied).
fn choose_format(
    ctx: &Context,
    formats: &[vk::SurfaceFormatKHR],
) -> Result<(vk::SurfaceFormatKHR, bool), VkError> {
    let pd = ctx.physical_device;
    // The output holds sRGB-encoded bytes in a UNORM image: the window
    // must show those bytes as they are. RGBA order takes a plain copy,
    // which moves bytes unchanged into a UNORM or an sRGB image (both
    // show encoded bytes in the sRGB colour space); BGRA a blit, which
    // swaps the channels exactly only into a UNORM image (into an sRGB
    // one it would encode the encoded values again).
    let srgb = vk::ColorSpaceKHR::SRGB_NONLINEAR;
    let pick = |f: vk::Format| {
        formats
            .iter()
            .find(|s| s.format == f && s.color_space == srgb)
            .copied()
    };
    let copied = pick(vk::Format::R8G8B8A8_UNORM).or_else(|| pick(vk::Format::R8G8B8A8_SRGB));
    let (chosen, blit) = match (copied, pick(vk::Format::B8G8R8A8_UNORM)) {
        (Some(f), _) => (f, false),
        (None, Some(f)) => (f, true),
        (None, None) => {
            return Err(VkError::Surface(format!(
                "the window offers no 8-bit format that shows sRGB-encoded bytes as they are \
                 (R8G8B8A8_UNORM, R8G8B8A8_SRGB or B8G8R8A8_UNORM in the sRGB colour space); \
                 it offers {:?}",
                formats.iter().map(|f| f.format).collect::<Vec<_>>()
            )))
        }
    };
    if blit {
        // SAFETY: valid physical device.
        let src = unsafe {
            ctx.instance
                .get_physical_device_format_properties(pd, SOURCE_FORMAT)
        };
        // SAFETY: valid physical device.
        let dst = unsafe {
            ctx.instance
                .get_physical_device_format_properties(pd, chosen.format)
        };
        if !src
            .optimal_tiling_features
            .contains(vk::FormatFeatureFlags::BLIT_SRC)
            || !dst
                .optimal_tiling_features
                .contains(vk::FormatFeatureFlags::BLIT_DST)
        {
            return Err(VkError::Surface(format!(
                "the window's format {:?} cannot be blitted to from {SOURCE_FORMAT:?} on this device",
                chosen.format
            )));
        }
    }
    Ok((chosen, blit))
}

/// The images' size: the surface's own where it has one, else about
/// `width`×`height` within the surface's bounds; refused without area.
fn choose_extent(
    caps: &vk::SurfaceCapabilitiesKHR,
    width: u32,
    height: u32,
) -> Result<vk::Extent2D, VkError> {
    let extent = if caps.current_extent.width != u32::MAX {
        caps.current_extent
    } else {
        vk::Extent2D {
            width: width.clamp(caps.min_image_extent.width, caps.max_image_extent.width),
            height: height.clamp(caps.min_image_extent.height, caps.max_image_extent.height),
        }
    };
    if extent.width == 0 || extent.height == 0 {
        return Err(VkError::Surface(
            "the window has no area (minimized); no swapchain can be made for it".into(),
        ));
    }
    Ok(extent)
}

/// One more image than the minimum, so acquiring never waits for the
/// presentation engine to release one; three where allowed.
fn image_count(caps: &vk::SurfaceCapabilitiesKHR) -> u32 {
    let count = (caps.min_image_count + 1).max(3);
    if caps.max_image_count != 0 {
        count.min(caps.max_image_count)
    } else {
        count
    }
}

/// Opaque composition where the surface offers it, else the first mode it
/// offers of the others.
fn composite_alpha(caps: &vk::SurfaceCapabilitiesKHR) -> vk::CompositeAlphaFlagsKHR {
    [
        vk::CompositeAlphaFlagsKHR::OPAQUE,
        vk::CompositeAlphaFlagsKHR::INHERIT,
        vk::CompositeAlphaFlagsKHR::PRE_MULTIPLIED,
        vk::CompositeAlphaFlagsKHR::POST_MULTIPLIED,
    ]
    .into_iter()
    .find(|a| caps.supported_composite_alpha.contains(*a))
    .unwrap_or(vk::CompositeAlphaFlagsKHR::OPAQUE)
}

impl Swapchain {
    /// A swapchain for `surface` of about `width`×`height` (the surface's
    /// own size when it has one), presenting with `mode`. `old` is the
    /// swapchain it replaces, if any (destroyed once this one exists).
    pub fn new(
        ctx: &Arc<Context>,
        surface: &Arc<Surface>,
        width: u32,
        height: u32,
        mode: PresentMode,
        old: Option<Swapchain>,
    ) -> Result<Swapchain, VkError> {
        let pd = ctx.physical_device;
        let s = &surface.loader;
        // SAFETY (the three queries): valid physical device and surface.
        let caps = unsafe { s.get_physical_device_surface_capabilities(pd, surface.handle) }?;
        // SAFETY: as above.
        let formats = unsafe { s.get_physical_device_surface_formats(pd, surface.handle) }?;
        // SAFETY: as above.
        let modes = unsafe { s.get_physical_device_surface_present_modes(pd, surface.handle) }?;

        if !modes.contains(&mode.vk()) {
            return Err(VkError::Surface(format!(
                "present mode {mode:?} is not supported by this window; it offers {:?}",
                modes
            )));
        }
        let (chosen, blit) = choose_format(ctx, &formats)?;
        if !caps
            .supported_usage_flags
            .contains(vk::ImageUsageFlags::TRANSFER_DST)
        {
            return Err(VkError::Surface(
                "the window's images cannot be copied to (no TRANSFER_DST usage)".into(),
            ));
        }
        let extent = choose_extent(&caps, width, height)?;
        let info = vk::SwapchainCreateInfoKHR::default()
            .surface(surface.handle)
            .min_image_count(image_count(&caps))
            .image_format(chosen.format)
            .image_color_space(chosen.color_space)
            .image_extent(extent)
            .image_array_layers(1)
            .image_usage(vk::ImageUsageFlags::TRANSFER_DST)
            .image_sharing_mode(vk::SharingMode::EXCLUSIVE)
            .pre_transform(caps.current_transform)
            .composite_alpha(composite_alpha(&caps))
            .present_mode(mode.vk())
            .clipped(true)
            .old_swapchain(old.as_ref().map_or(vk::SwapchainKHR::null(), |o| o.handle));
        let loader = ash::khr::swapchain::Device::new(&ctx.instance, &ctx.device);
        // SAFETY: the surface and the old swapchain (retired by this call)
        // are alive; the create info points at locals.
        let handle = unsafe { loader.create_swapchain(&info, None) }?;
        // The old swapchain's images may still be in use by its last
        // present; its Drop waits for the device before destroying it.
        drop(old);
        let mut swapchain = Swapchain {
            ctx: ctx.clone(),
            surface: surface.clone(),
            loader,
            handle,
            images: Vec::new(),
            format: chosen.format,
            blit,
            width: extent.width,
            height: extent.height,
            acquired: vk::Semaphore::null(),
            copied: Vec::new(),
            fence: vk::Fence::null(),
            pool: vk::CommandPool::null(),
            cmd: vk::CommandBuffer::null(),
        };
        // From here, Drop destroys whatever was created.
        // SAFETY: the swapchain was just created.
        swapchain.images = unsafe { swapchain.loader.get_swapchain_images(handle) }?;
        swapchain.create_frame_objects()?;
        Ok(swapchain)
    }

    /// The semaphores, the fence and the command pool and buffer a frame
    /// needs, stored as each is created so that Drop destroys them.
    fn create_frame_objects(&mut self) -> Result<(), VkError> {
        let device = &self.ctx.device;
        // SAFETY: valid device; each handle is stored at once so Drop
        // destroys it.
        unsafe {
            self.acquired = device.create_semaphore(&Default::default(), None)?;
            for _ in 0..self.images.len() {
                let s = device.create_semaphore(&Default::default(), None)?;
                self.copied.push(s);
            }
            self.fence = device.create_fence(&Default::default(), None)?;
            self.pool = device.create_command_pool(
                &vk::CommandPoolCreateInfo::default()
                    .flags(vk::CommandPoolCreateFlags::TRANSIENT)
                    .queue_family_index(self.ctx.queue_family),
                None,
            )?;
            self.cmd = device.allocate_command_buffers(
                &vk::CommandBufferAllocateInfo::default()
                    .command_pool(self.pool)
                    .level(vk::CommandBufferLevel::PRIMARY)
                    .command_buffer_count(1),
            )?[0];
        }
        Ok(())
    }

    /// The size of the images, which the presented source must have.
    pub fn extent(&self) -> (u32, u32) {
        (self.width, self.height)
    }

    /// The images' format.
    pub fn format(&self) -> vk::Format {
        self.format
    }

    /// Copies `source` into the next swapchain image and presents it,
    /// waiting until the copy is done. `source` must be an 8-bit sRGB RGBA
    /// image of the swapchain's size that the commands submitted before
    /// left in `TRANSFER_SRC_OPTIMAL` (the renderer's output after its
    /// readback); those commands' dependency into later transfers makes
    /// their writes visible to the copy.
    pub fn present(&mut self, source: &Image) -> Result<Presented, VkError> {
        if source.layout() != vk::ImageLayout::TRANSFER_SRC_OPTIMAL
            || source.desc.format != SOURCE_FORMAT
            || (source.desc.width, source.desc.height) != (self.width, self.height)
        {
            return Err(VkError::Graph(format!(
                "presenting a {}x{} {:?} image in {:?} to a {}x{} swapchain; expected {SOURCE_FORMAT:?} in TRANSFER_SRC_OPTIMAL of the same size",
                source.desc.width,
                source.desc.height,
                source.desc.format,
                source.layout(),
                self.width,
                self.height
            )));
        }
        // SAFETY: the swapchain is alive; `acquired` is unsignalled (every
        // earlier acquire's signal was waited on by the copy submitted
        // after it, which the fence then waited for).
        let acquire = unsafe {
            self.loader
                .acquire_next_image(self.handle, u64::MAX, self.acquired, vk::Fence::null())
        };
        let (index, acquire_suboptimal) = match acquire {
            Ok(r) => r,
            Err(vk::Result::ERROR_OUT_OF_DATE_KHR) => return Ok(Presented::OutOfDate),
            Err(e) => return Err(e.into()),
        };
        let target = self.images[index as usize];
        let copied = self.copied[index as usize];
        self.record_copy(source, target)?;
        let device = &self.ctx.device;
        let waits = [self.acquired];
        let wait_stages = [vk::PipelineStageFlags::TRANSFER];
        let buffers = [self.cmd];
        let signals = [copied];
        let submit = vk::SubmitInfo::default()
            .wait_semaphores(&waits)
            .wait_dst_stage_mask(&wait_stages)
            .command_buffers(&buffers)
            .signal_semaphores(&signals);
        // SAFETY: the command buffer is recorded; the fence is unsignalled
        // (reset after every wait); `copied` for this image is not awaited
        // by a pending present (that present finished before the image
        // could be acquired again).
        unsafe {
            device.queue_submit(self.ctx.queue, &[submit], self.fence)?;
            device.wait_for_fences(&[self.fence], true, u64::MAX)?;
            device.reset_fences(&[self.fence])?;
        }
        let swapchains = [self.handle];
        let indices = [index];
        let present = vk::PresentInfoKHR::default()
            .wait_semaphores(&signals)
            .swapchains(&swapchains)
            .image_indices(&indices);
        // SAFETY: the image was acquired and its copy submitted, signalling
        // the semaphore the present waits on.
        let presented = unsafe { self.loader.queue_present(self.ctx.queue, &present) };
        match presented {
            Ok(false) if !acquire_suboptimal => Ok(Presented::Done),
            Ok(_) => Ok(Presented::Suboptimal),
            Err(vk::Result::ERROR_OUT_OF_DATE_KHR) => Ok(Presented::OutOfDate),
            Err(e) => Err(e.into()),
        }
    }

    /// Records: the swapchain image to TRANSFER_DST (its old contents are
    /// not needed), the copy or blit from `source`, then the image to
    /// PRESENT_SRC.
    fn record_copy(&self, source: &Image, target: vk::Image) -> Result<(), VkError> {
        let device = &self.ctx.device;
        let range = vk::ImageSubresourceRange {
            aspect_mask: vk::ImageAspectFlags::COLOR,
            base_mip_level: 0,
            level_count: 1,
            base_array_layer: 0,
            layer_count: 1,
        };
        let layers = vk::ImageSubresourceLayers {
            aspect_mask: vk::ImageAspectFlags::COLOR,
            mip_level: 0,
            base_array_layer: 0,
            layer_count: 1,
        };
        let barrier = |old: vk::ImageLayout,
                       new: vk::ImageLayout,
                       src: vk::AccessFlags,
                       dst: vk::AccessFlags| {
            vk::ImageMemoryBarrier::default()
                .old_layout(old)
                .new_layout(new)
                .src_access_mask(src)
                .dst_access_mask(dst)
                .src_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
                .dst_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
                .image(target)
                .subresource_range(range)
        };
        let to_transfer = barrier(
            vk::ImageLayout::UNDEFINED,
            vk::ImageLayout::TRANSFER_DST_OPTIMAL,
            vk::AccessFlags::empty(),
            vk::AccessFlags::TRANSFER_WRITE,
        );
        let to_present = barrier(
            vk::ImageLayout::TRANSFER_DST_OPTIMAL,
            vk::ImageLayout::PRESENT_SRC_KHR,
            vk::AccessFlags::TRANSFER_WRITE,
            vk::AccessFlags::empty(),
        );
        let (w, h) = (self.width, self.height);
        // SAFETY: the previous use of the command buffer finished (present
        // waits for its fence), so the pool may be reset; the images are
        // alive; the source is in TRANSFER_SRC_OPTIMAL (checked by the
        // caller) and the target is moved to TRANSFER_DST_OPTIMAL first.
        // The first barrier's source stage is the stage the acquire
        // semaphore is waited at, which chains it after the acquire.
        unsafe {
            device.reset_command_pool(self.pool, vk::CommandPoolResetFlags::empty())?;
            device.begin_command_buffer(
                self.cmd,
                &vk::CommandBufferBeginInfo::default()
                    .flags(vk::CommandBufferUsageFlags::ONE_TIME_SUBMIT),
            )?;
            device.cmd_pipeline_barrier(
                self.cmd,
                vk::PipelineStageFlags::TRANSFER,
                vk::PipelineStageFlags::TRANSFER,
                vk::DependencyFlags::empty(),
                &[],
                &[],
                &[to_transfer],
            );
            if self.blit {
                let corner = vk::Offset3D {
                    x: w as i32,
                    y: h as i32,
                    z: 1,
                };
                let region = vk::ImageBlit::default()
                    .src_subresource(layers)
                    .src_offsets([vk::Offset3D::default(), corner])
                    .dst_subresource(layers)
                    .dst_offsets([vk::Offset3D::default(), corner]);
                device.cmd_blit_image(
                    self.cmd,
                    source.handle,
                    vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
                    target,
                    vk::ImageLayout::TRANSFER_DST_OPTIMAL,
                    &[region],
                    vk::Filter::NEAREST,
                );
            } else {
                let region = vk::ImageCopy::default()
                    .src_subresource(layers)
                    .dst_subresource(layers)
                    .extent(vk::Extent3D {
                        width: w,
                        height: h,
                        depth: 1,
                    });
                device.cmd_copy_image(
                    self.cmd,
                    source.handle,
                    vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
                    target,
                    vk::ImageLayout::TRANSFER_DST_OPTIMAL,
                    &[region],
                );
            }
            device.cmd_pipeline_barrier(
                self.cmd,
                vk::PipelineStageFlags::TRANSFER,
                vk::PipelineStageFlags::BOTTOM_OF_PIPE,
                vk::DependencyFlags::empty(),
                &[],
                &[],
                &[to_present],
            );
            device.end_command_buffer(self.cmd)?;
        }
        Ok(())
    }
}

impl Drop for Swapchain {
    fn drop(&mut self) {
        // SAFETY: after the wait nothing of this swapchain is pending (each
        // copy was waited for by its fence; the wait covers the presents'
        // semaphore waits); null handles (a failed `new`) are skipped.
        unsafe {
            let device = &self.ctx.device;
            let _ = device.device_wait_idle();
            if self.pool != vk::CommandPool::null() {
                device.destroy_command_pool(self.pool, None);
            }
            if self.fence != vk::Fence::null() {
                device.destroy_fence(self.fence, None);
            }
            for s in self.copied.drain(..) {
                device.destroy_semaphore(s, None);
            }
            if self.acquired != vk::Semaphore::null() {
                device.destroy_semaphore(self.acquired, None);
            }
            self.loader.destroy_swapchain(self.handle, None);
        }
        let _ = &self.surface;
    }
}
