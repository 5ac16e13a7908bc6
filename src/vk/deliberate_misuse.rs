//! Deliberate mistakes, made only to prove that validation catches them.
//!
//! A validation run that reports nothing is only evidence when the layer
//! would have reported a mistake. The tests make one of each kind the
//! documentation promises is caught (an API misuse, a synchronization
//! hazard, an object leaked at teardown) and assert the message arrives.
//!
//! Compiled only with the `deliberate-misuse` feature, which the test
//! suite turns on through its dev-dependency on this crate: the shipped
//! library and binary have no way to make these mistakes.

use super::{Context, VkError};
use ash::vk;
use gpu_allocator::vulkan::{AllocationCreateDesc, AllocationScheme};
use gpu_allocator::MemoryLocation;

impl Context {
    /// Makes one deliberate API misuse (a sampler with anisotropic
    /// filtering, whose device feature was not enabled) so a caller can
    /// check that the validation messenger is live and counting. The
    /// sampler is destroyed again at once.
    pub fn misuse_api_for_validation_check(&self) -> Result<(), VkError> {
        let info = vk::SamplerCreateInfo::default()
            .anisotropy_enable(true)
            .max_anisotropy(4.0);
        // SAFETY: the only invalid part is the disabled feature, which
        // drivers ignore; the sampler is never used.
        let sampler = unsafe { self.device.create_sampler(&info, None) }?;
        // SAFETY: created above, unused.
        unsafe { self.device.destroy_sampler(sampler, None) };
        Ok(())
    }

    /// Records (but never submits) a command buffer that clears one image
    /// twice with no barrier between the clears: a write-after-write
    /// hazard that only synchronization validation reports. Everything it
    /// creates is destroyed again before it returns.
    pub fn record_sync_hazard_for_validation_check(&self) -> Result<(), VkError> {
        let image_info = vk::ImageCreateInfo::default()
            .image_type(vk::ImageType::TYPE_2D)
            .format(vk::Format::R8G8B8A8_UNORM)
            .extent(vk::Extent3D {
                width: 4,
                height: 4,
                depth: 1,
            })
            .mip_levels(1)
            .array_layers(1)
            .samples(vk::SampleCountFlags::TYPE_1)
            .tiling(vk::ImageTiling::OPTIMAL)
            .usage(vk::ImageUsageFlags::TRANSFER_DST)
            .initial_layout(vk::ImageLayout::UNDEFINED);
        // SAFETY: valid device; the create info points at locals.
        let image = unsafe { self.device.create_image(&image_info, None) }?;
        // SAFETY: image was created from this device.
        let requirements = unsafe { self.device.get_image_memory_requirements(image) };
        let allocation = match self.allocator().allocate(&AllocationCreateDesc {
            name: "sync hazard check",
            requirements,
            location: MemoryLocation::GpuOnly,
            linear: false,
            allocation_scheme: AllocationScheme::GpuAllocatorManaged,
        }) {
            Ok(a) => a,
            Err(e) => {
                // SAFETY: unbound, unused image.
                unsafe { self.device.destroy_image(image, None) };
                return Err(e.into());
            }
        };
        let result = self.record_double_clear(image, &allocation);
        // SAFETY: the command buffer that referenced the image was never
        // submitted and is freed with its pool inside record_double_clear.
        unsafe { self.device.destroy_image(image, None) };
        let _ = self.allocator().free(allocation);
        result
    }

    fn record_double_clear(
        &self,
        image: vk::Image,
        allocation: &gpu_allocator::vulkan::Allocation,
    ) -> Result<(), VkError> {
        // SAFETY: the memory comes from this device's allocator, sized and
        // aligned for the image's requirements.
        unsafe {
            self.device
                .bind_image_memory(image, allocation.memory(), allocation.offset())
        }?;
        let pool_info = vk::CommandPoolCreateInfo::default().queue_family_index(self.queue_family);
        // SAFETY: valid device and queue family.
        let pool = unsafe { self.device.create_command_pool(&pool_info, None) }?;
        let record = || -> Result<(), VkError> {
            let alloc_info = vk::CommandBufferAllocateInfo::default()
                .command_pool(pool)
                .level(vk::CommandBufferLevel::PRIMARY)
                .command_buffer_count(1);
            // SAFETY: pool is valid and used by this thread only.
            let cmd = unsafe { self.device.allocate_command_buffers(&alloc_info) }?[0];
            let range = vk::ImageSubresourceRange::default()
                .aspect_mask(vk::ImageAspectFlags::COLOR)
                .level_count(1)
                .layer_count(1);
            // The layout transition is correctly ordered before the first
            // clear, so the only hazard is the one between the two clears.
            let to_dst = vk::ImageMemoryBarrier::default()
                .src_access_mask(vk::AccessFlags::empty())
                .dst_access_mask(vk::AccessFlags::TRANSFER_WRITE)
                .old_layout(vk::ImageLayout::UNDEFINED)
                .new_layout(vk::ImageLayout::TRANSFER_DST_OPTIMAL)
                .src_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
                .dst_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
                .image(image)
                .subresource_range(range);
            let clear = vk::ClearColorValue {
                float32: [1.0, 0.0, 0.0, 1.0],
            };
            // SAFETY: cmd is in the initial state; the image is bound to
            // memory and in TRANSFER_DST_OPTIMAL after the barrier. The
            // missing barrier between the clears is the point; the buffer
            // is never submitted.
            unsafe {
                self.device
                    .begin_command_buffer(cmd, &vk::CommandBufferBeginInfo::default())?;
                self.device.cmd_pipeline_barrier(
                    cmd,
                    vk::PipelineStageFlags::TOP_OF_PIPE,
                    vk::PipelineStageFlags::TRANSFER,
                    vk::DependencyFlags::empty(),
                    &[],
                    &[],
                    &[to_dst],
                );
                for _ in 0..2 {
                    self.device.cmd_clear_color_image(
                        cmd,
                        image,
                        vk::ImageLayout::TRANSFER_DST_OPTIMAL,
                        &clear,
                        &[range],
                    );
                }
                self.device.end_command_buffer(cmd)?;
            }
            Ok(())
        };
        let result = record();
        // SAFETY: nothing from the pool was submitted.
        unsafe { self.device.destroy_command_pool(pool, None) };
        result
    }

    /// The error a deliberately failed run returns, so the tests can check
    /// that a failed run still reports what the layer said.
    pub fn deliberate_failure_for_validation_check() -> VkError {
        VkError::Api(vk::Result::ERROR_UNKNOWN)
    }

    /// Creates a sampler and never destroys it, so destroying the device
    /// leaks it: the object-lifetime check reports that while the device
    /// is destroyed, after every frame is done.
    pub fn leak_object_for_validation_check(&self) -> Result<(), VkError> {
        // SAFETY: a plain, valid sampler; leaking a handle is invalid use
        // the layer reports, not memory unsafety (the driver frees it with
        // the device).
        unsafe {
            self.device
                .create_sampler(&vk::SamplerCreateInfo::default(), None)
        }?;
        Ok(())
    }
}
