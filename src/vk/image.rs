//! Images (attachments and textures), their views, and samplers.

use super::{Context, VkError};
use ash::vk;
use gpu_allocator::vulkan::{Allocation, AllocationCreateDesc, AllocationScheme};
use gpu_allocator::MemoryLocation;
use std::cell::Cell;
use std::sync::Arc;

/// What to create: a 2D image with one view over all its mip levels.
#[derive(Clone, Copy, Debug)]
pub struct ImageDesc {
    pub width: u32,
    pub height: u32,
    pub format: vk::Format,
    pub usage: vk::ImageUsageFlags,
    pub mip_levels: u32,
    pub aspect: vk::ImageAspectFlags,
}

/// Where an image stands in the command stream being recorded: its layout,
/// and the last stages and accesses that touched it, so the next use can
/// derive its barrier (see `CommandBuffer::transition`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct ImageState {
    pub layout: vk::ImageLayout,
    pub stage: vk::PipelineStageFlags,
    /// Writes not yet made visible to later uses (empty after reads, or when
    /// a dependency already made them visible).
    pub pending_writes: vk::AccessFlags,
}

impl ImageState {
    pub(crate) const UNDEFINED: ImageState = ImageState {
        layout: vk::ImageLayout::UNDEFINED,
        stage: vk::PipelineStageFlags::TOP_OF_PIPE,
        pending_writes: vk::AccessFlags::empty(),
    };
}

/// A device-local 2D (or 3D, [`Image::new_volume`]) image with its view, which knows its current layout
/// while commands are recorded.
pub struct Image {
    ctx: Arc<Context>,
    pub(crate) handle: vk::Image,
    pub(crate) view: vk::ImageView,
    allocation: Option<Allocation>,
    pub desc: ImageDesc,
    /// The state after the commands recorded so far (every mip level
    /// together; mip generation handles levels itself and leaves them
    /// uniform).
    pub(crate) state: Cell<ImageState>,
}

impl Image {
    pub fn new(ctx: &Arc<Context>, name: &str, desc: ImageDesc) -> Result<Image, VkError> {
        Image::create(ctx, name, desc, None)
    }

    /// A 3D image of `desc.width` × `desc.height` × `depth` texels, one mip
    /// level, for tables a shader writes and samples in three dimensions.
    pub fn new_volume(
        ctx: &Arc<Context>,
        name: &str,
        desc: ImageDesc,
        depth: u32,
    ) -> Result<Image, VkError> {
        let max = ctx.limits.max_image_dimension3_d;
        if [desc.width, desc.height, depth]
            .iter()
            .any(|&n| n == 0 || n > max)
            || desc.mip_levels != 1
        {
            return Err(VkError::ImageSize {
                name: format!("{name} (depth {depth})"),
                width: desc.width,
                height: desc.height,
                max_width: max,
                max_height: max,
                limit: "maxImageDimension3D",
            });
        }
        Image::create(ctx, name, desc, Some(depth))
    }

    /// A 2D image, or a 3D one of `volume` slices.
    fn create(
        ctx: &Arc<Context>,
        name: &str,
        desc: ImageDesc,
        volume: Option<u32>,
    ) -> Result<Image, VkError> {
        check_format(ctx, desc.format, desc.usage)?;
        if volume.is_none() {
            check_size(ctx, name, &desc)?;
        }
        let (image_type, view_type) = match volume {
            Some(_) => (vk::ImageType::TYPE_3D, vk::ImageViewType::TYPE_3D),
            None => (vk::ImageType::TYPE_2D, vk::ImageViewType::TYPE_2D),
        };
        let info = vk::ImageCreateInfo::default()
            .image_type(image_type)
            .format(desc.format)
            .extent(vk::Extent3D {
                width: desc.width,
                height: desc.height,
                depth: volume.unwrap_or(1),
            })
            .mip_levels(desc.mip_levels)
            .array_layers(1)
            .samples(vk::SampleCountFlags::TYPE_1)
            .tiling(vk::ImageTiling::OPTIMAL)
            .usage(desc.usage)
            .sharing_mode(vk::SharingMode::EXCLUSIVE)
            .initial_layout(vk::ImageLayout::UNDEFINED);
        // SAFETY: valid device; format support checked above.
        let handle = unsafe { ctx.device.create_image(&info, None) }?;
        // From here, `image` owns the handle and cleans up on early return.
        let mut image = Image {
            ctx: ctx.clone(),
            handle,
            view: vk::ImageView::null(),
            allocation: None,
            desc,
            state: Cell::new(ImageState::UNDEFINED),
        };
        // SAFETY: handle was created on this device.
        let requirements = unsafe { ctx.device.get_image_memory_requirements(handle) };
        let allocation = ctx.allocator().allocate(&AllocationCreateDesc {
            name,
            requirements,
            location: MemoryLocation::GpuOnly,
            linear: false,
            allocation_scheme: AllocationScheme::GpuAllocatorManaged,
        })?;
        // SAFETY: memory satisfies the image's requirements; bound once.
        let bound = unsafe {
            ctx.device
                .bind_image_memory(handle, allocation.memory(), allocation.offset())
        };
        image.allocation = Some(allocation);
        bound?;
        let view_info = vk::ImageViewCreateInfo::default()
            .image(handle)
            .view_type(view_type)
            .format(desc.format)
            .subresource_range(image.full_range());
        // SAFETY: the image is bound to memory and the range is within it.
        image.view = unsafe { ctx.device.create_image_view(&view_info, None) }?;
        Ok(image)
    }

    /// The layout the recorded commands leave the image in.
    pub fn layout(&self) -> vk::ImageLayout {
        self.state.get().layout
    }

    /// Every mip level and the one layer.
    pub(crate) fn full_range(&self) -> vk::ImageSubresourceRange {
        vk::ImageSubresourceRange {
            aspect_mask: self.desc.aspect,
            base_mip_level: 0,
            level_count: self.desc.mip_levels,
            base_array_layer: 0,
            layer_count: 1,
        }
    }
}

/// A view of one mip level of an [`Image`], for shaders that read or
/// write that level alone (a storage image is written through a view of
/// one level). It does not keep the image alive: its owner drops it first.
pub struct MipView {
    ctx: Arc<Context>,
    pub(crate) view: vk::ImageView,
    /// The level it shows.
    pub level: u32,
}

impl Image {
    /// A view of mip `level` alone.
    pub fn mip_view(&self, level: u32) -> Result<MipView, VkError> {
        if level >= self.desc.mip_levels {
            return Err(VkError::Unsupported(format!(
                "mip level {level} of an image of {} levels",
                self.desc.mip_levels
            )));
        }
        let mut range = self.full_range();
        range.base_mip_level = level;
        range.level_count = 1;
        let info = vk::ImageViewCreateInfo::default()
            .image(self.handle)
            .view_type(vk::ImageViewType::TYPE_2D)
            .format(self.desc.format)
            .subresource_range(range);
        // SAFETY: the image is bound to memory and the level is within it
        // (checked above).
        let view = unsafe { self.ctx.device.create_image_view(&info, None) }?;
        Ok(MipView {
            ctx: self.ctx.clone(),
            view,
            level,
        })
    }
}

impl Drop for MipView {
    fn drop(&mut self) {
        // SAFETY: no pending command buffer uses the view (its owner waits
        // for the device before dropping it).
        unsafe { self.ctx.device.destroy_image_view(self.view, None) };
    }
}

/// Fails with a clear error when the image is larger than the device
/// allows (creating it would be invalid usage, not a reported error).
fn check_size(ctx: &Context, name: &str, desc: &ImageDesc) -> Result<(), VkError> {
    let l = &ctx.limits;
    let mut max = (l.max_image_dimension2_d, l.max_image_dimension2_d);
    let mut limit = "maxImageDimension2D";
    if desc.usage.intersects(
        vk::ImageUsageFlags::COLOR_ATTACHMENT | vk::ImageUsageFlags::DEPTH_STENCIL_ATTACHMENT,
    ) && (l.max_framebuffer_width, l.max_framebuffer_height) < max
    {
        max = (l.max_framebuffer_width, l.max_framebuffer_height);
        limit = "maxFramebufferWidth/Height";
    }
    let full_chain = 32 - desc.width.max(desc.height).leading_zeros();
    if desc.width == 0
        || desc.height == 0
        || desc.width > max.0
        || desc.height > max.1
        || desc.mip_levels == 0
        || desc.mip_levels > full_chain
    {
        return Err(VkError::ImageSize {
            name: name.to_string(),
            width: desc.width,
            height: desc.height,
            max_width: max.0,
            max_height: max.1,
            limit,
        });
    }
    Ok(())
}

/// Fails with a clear error when the device cannot use `format` as asked.
fn check_format(
    ctx: &Context,
    format: vk::Format,
    usage: vk::ImageUsageFlags,
) -> Result<(), VkError> {
    let have = optimal_tiling_features(ctx, format);
    let needs = [
        (
            vk::ImageUsageFlags::COLOR_ATTACHMENT,
            vk::FormatFeatureFlags::COLOR_ATTACHMENT,
            "colour attachment",
        ),
        (
            vk::ImageUsageFlags::DEPTH_STENCIL_ATTACHMENT,
            vk::FormatFeatureFlags::DEPTH_STENCIL_ATTACHMENT,
            "depth attachment",
        ),
        (
            vk::ImageUsageFlags::SAMPLED,
            vk::FormatFeatureFlags::SAMPLED_IMAGE,
            "sampling",
        ),
        (
            vk::ImageUsageFlags::STORAGE,
            vk::FormatFeatureFlags::STORAGE_IMAGE,
            "storage",
        ),
        (
            vk::ImageUsageFlags::TRANSFER_SRC,
            vk::FormatFeatureFlags::TRANSFER_SRC,
            "transfer source",
        ),
        (
            vk::ImageUsageFlags::TRANSFER_DST,
            vk::FormatFeatureFlags::TRANSFER_DST,
            "transfer destination",
        ),
    ];
    for (u, f, what) in needs {
        if usage.contains(u) && !have.contains(f) {
            return Err(VkError::UnsupportedFormat {
                format,
                what: what.to_string(),
            });
        }
    }
    Ok(())
}

/// Whether a sampler may filter `format` linearly (optimal tiling).
pub fn supports_linear_sampling(ctx: &Context, format: vk::Format) -> bool {
    has_features(
        ctx,
        format,
        vk::FormatFeatureFlags::SAMPLED_IMAGE_FILTER_LINEAR,
    )
}

/// Whether `format` can be blitted into itself with a linear filter (how
/// mip chains are built), and sampled linearly afterwards.
pub fn supports_linear_blits(ctx: &Context, format: vk::Format) -> bool {
    has_features(
        ctx,
        format,
        vk::FormatFeatureFlags::SAMPLED_IMAGE_FILTER_LINEAR
            | vk::FormatFeatureFlags::BLIT_SRC
            | vk::FormatFeatureFlags::BLIT_DST,
    )
}

fn has_features(ctx: &Context, format: vk::Format, features: vk::FormatFeatureFlags) -> bool {
    optimal_tiling_features(ctx, format).contains(features)
}

/// What the device supports for `format` with optimal tiling.
fn optimal_tiling_features(ctx: &Context, format: vk::Format) -> vk::FormatFeatureFlags {
    // SAFETY: valid physical device of this instance.
    unsafe {
        ctx.instance
            .get_physical_device_format_properties(ctx.physical_device, format)
    }
    .optimal_tiling_features
}

impl Drop for Image {
    fn drop(&mut self) {
        // SAFETY: owners drop images only after the GPU finished with them.
        unsafe {
            if self.view != vk::ImageView::null() {
                self.ctx.device.destroy_image_view(self.view, None);
            }
            self.ctx.device.destroy_image(self.handle, None);
        }
        if let Some(a) = self.allocation.take() {
            let _ = self.ctx.allocator().free(a);
        }
    }
}

/// How a sampler filters.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SamplerFilter {
    /// Nearest texel of the nearest mip level.
    Nearest,
    /// Bilinear within the nearest mip level.
    Bilinear,
    /// Bilinear within and linear between mip levels.
    Trilinear,
}

/// A sampler.
pub struct Sampler {
    ctx: Arc<Context>,
    pub(crate) handle: vk::Sampler,
}

impl Sampler {
    /// A sampler with repeat addressing over `mip_levels`.
    pub fn new(
        ctx: &Arc<Context>,
        filtering: SamplerFilter,
        mip_levels: u32,
    ) -> Result<Sampler, VkError> {
        Sampler::with_addressing(ctx, filtering, mip_levels, vk::SamplerAddressMode::REPEAT)
    }

    /// A sampler of one mip level that clamps coordinates to the edge
    /// texels (tables: nothing wraps around).
    pub fn clamped(ctx: &Arc<Context>, filtering: SamplerFilter) -> Result<Sampler, VkError> {
        Sampler::with_addressing(ctx, filtering, 1, vk::SamplerAddressMode::CLAMP_TO_EDGE)
    }

    /// A shadow-map sampler: one depth comparison (LESS_OR_EQUAL: 1 where
    /// the reference is no farther than the stored depth) at the nearest
    /// texel, and outside the map the border's depth 1, so a point the map
    /// does not cover is lit.
    pub fn depth_comparison(ctx: &Arc<Context>) -> Result<Sampler, VkError> {
        let border = vk::SamplerAddressMode::CLAMP_TO_BORDER;
        let info = vk::SamplerCreateInfo::default()
            .mag_filter(vk::Filter::NEAREST)
            .min_filter(vk::Filter::NEAREST)
            .mipmap_mode(vk::SamplerMipmapMode::NEAREST)
            .address_mode_u(border)
            .address_mode_v(border)
            .address_mode_w(border)
            .border_color(vk::BorderColor::FLOAT_OPAQUE_WHITE)
            .compare_enable(true)
            .compare_op(vk::CompareOp::LESS_OR_EQUAL)
            .min_lod(0.0)
            .max_lod(1.0);
        // SAFETY: valid device; a core border colour, no anisotropy.
        let handle = unsafe { ctx.device.create_sampler(&info, None) }?;
        Ok(Sampler {
            ctx: ctx.clone(),
            handle,
        })
    }

    fn with_addressing(
        ctx: &Arc<Context>,
        filtering: SamplerFilter,
        mip_levels: u32,
        addressing: vk::SamplerAddressMode,
    ) -> Result<Sampler, VkError> {
        let (filter, mip) = match filtering {
            SamplerFilter::Nearest => (vk::Filter::NEAREST, vk::SamplerMipmapMode::NEAREST),
            SamplerFilter::Bilinear => (vk::Filter::LINEAR, vk::SamplerMipmapMode::NEAREST),
            SamplerFilter::Trilinear => (vk::Filter::LINEAR, vk::SamplerMipmapMode::LINEAR),
        };
        let info = vk::SamplerCreateInfo::default()
            .mag_filter(filter)
            .min_filter(filter)
            .mipmap_mode(mip)
            .address_mode_u(addressing)
            .address_mode_v(addressing)
            .address_mode_w(addressing)
            .min_lod(0.0)
            .max_lod(mip_levels as f32);
        // SAFETY: valid device; anisotropy stays disabled (feature not enabled).
        let handle = unsafe { ctx.device.create_sampler(&info, None) }?;
        Ok(Sampler {
            ctx: ctx.clone(),
            handle,
        })
    }
}

impl Drop for Sampler {
    fn drop(&mut self) {
        // SAFETY: no command buffer using the sampler is pending.
        unsafe { self.ctx.device.destroy_sampler(self.handle, None) };
    }
}

/// Bytes per texel of the colour and depth formats this crate creates
/// images in (and, for any other, the common 4): the one table that sizes
/// read-back buffers and memory estimates.
pub fn bytes_per_texel(format: vk::Format) -> u64 {
    match format {
        vk::Format::R32G32B32A32_SFLOAT => 16,
        vk::Format::R32G32B32_SFLOAT => 12,
        vk::Format::R16G16B16A16_SFLOAT
        | vk::Format::R16G16B16A16_UNORM
        | vk::Format::R32G32_SFLOAT
        | vk::Format::D32_SFLOAT_S8_UINT => 8,
        vk::Format::D16_UNORM => 2,
        _ => 4,
    }
}
