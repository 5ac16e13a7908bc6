//! Descriptor set layouts, pools and sets.

use super::{Buffer, Context, Image, MipView, Sampler, VkError};
use ash::vk;
use std::sync::Arc;

/// One binding of a set layout.
#[derive(Clone, Copy, Debug)]
pub struct DescriptorBinding {
    pub binding: u32,
    pub kind: vk::DescriptorType,
    pub stages: vk::ShaderStageFlags,
}

pub struct DescriptorSetLayout {
    ctx: Arc<Context>,
    pub(crate) handle: vk::DescriptorSetLayout,
    pub(crate) bindings: Vec<DescriptorBinding>,
}

impl DescriptorSetLayout {
    pub fn new(
        ctx: &Arc<Context>,
        bindings: &[DescriptorBinding],
    ) -> Result<DescriptorSetLayout, VkError> {
        let raw: Vec<_> = bindings
            .iter()
            .map(|b| {
                vk::DescriptorSetLayoutBinding::default()
                    .binding(b.binding)
                    .descriptor_type(b.kind)
                    .descriptor_count(1)
                    .stage_flags(b.stages)
            })
            .collect();
        let info = vk::DescriptorSetLayoutCreateInfo::default().bindings(&raw);
        // SAFETY: valid device and bindings.
        let handle = unsafe { ctx.device.create_descriptor_set_layout(&info, None) }?;
        Ok(DescriptorSetLayout {
            ctx: ctx.clone(),
            handle,
            bindings: bindings.to_vec(),
        })
    }
}

impl Drop for DescriptorSetLayout {
    fn drop(&mut self) {
        // SAFETY: pipelines and sets created from it are not in use.
        unsafe {
            self.ctx
                .device
                .destroy_descriptor_set_layout(self.handle, None)
        };
    }
}

/// A pool sized exactly for the given layouts (one set each).
pub struct DescriptorPool {
    ctx: Arc<Context>,
    handle: vk::DescriptorPool,
}

impl DescriptorPool {
    pub fn for_layouts(
        ctx: &Arc<Context>,
        layouts: &[&DescriptorSetLayout],
    ) -> Result<DescriptorPool, VkError> {
        let mut sizes: Vec<vk::DescriptorPoolSize> = Vec::new();
        for b in layouts.iter().flat_map(|l| &l.bindings) {
            match sizes.iter_mut().find(|s| s.ty == b.kind) {
                Some(s) => s.descriptor_count += 1,
                None => sizes.push(vk::DescriptorPoolSize {
                    ty: b.kind,
                    descriptor_count: 1,
                }),
            }
        }
        let info = vk::DescriptorPoolCreateInfo::default()
            .max_sets(layouts.len().max(1) as u32)
            .pool_sizes(&sizes);
        // SAFETY: valid device.
        let handle = unsafe { ctx.device.create_descriptor_pool(&info, None) }?;
        Ok(DescriptorPool {
            ctx: ctx.clone(),
            handle,
        })
    }

    /// Allocates one set of `layout` from the pool.
    pub fn allocate(&self, layout: &DescriptorSetLayout) -> Result<DescriptorSet, VkError> {
        let layouts = [layout.handle];
        let info = vk::DescriptorSetAllocateInfo::default()
            .descriptor_pool(self.handle)
            .set_layouts(&layouts);
        // SAFETY: the pool was sized for this layout.
        let handle = unsafe { self.ctx.device.allocate_descriptor_sets(&info) }?[0];
        Ok(DescriptorSet {
            ctx: self.ctx.clone(),
            handle,
        })
    }
}

impl Drop for DescriptorPool {
    fn drop(&mut self) {
        // SAFETY: destroying the pool frees its sets; none is in use.
        unsafe { self.ctx.device.destroy_descriptor_pool(self.handle, None) };
    }
}

/// A descriptor set; freed with its pool.
pub struct DescriptorSet {
    ctx: Arc<Context>,
    pub(crate) handle: vk::DescriptorSet,
}

impl DescriptorSet {
    /// Points `binding` at `range` bytes of `buffer` (a uniform or storage
    /// buffer, dynamic or not, as the layout says).
    pub fn write_buffer(
        &self,
        binding: u32,
        kind: vk::DescriptorType,
        buffer: &Buffer,
        range: u64,
    ) {
        let infos = [vk::DescriptorBufferInfo {
            buffer: buffer.handle,
            offset: 0,
            range,
        }];
        let write = vk::WriteDescriptorSet::default()
            .dst_set(self.handle)
            .dst_binding(binding)
            .descriptor_type(kind)
            .buffer_info(&infos);
        // SAFETY: the set is not in use by a pending command buffer.
        unsafe { self.ctx.device.update_descriptor_sets(&[write], &[]) };
    }

    /// Points `binding` at a sampled image in SHADER_READ_ONLY_OPTIMAL.
    pub fn write_sampled_image(&self, binding: u32, image: &Image, sampler: &Sampler) {
        self.write_image(
            binding,
            vk::DescriptorType::COMBINED_IMAGE_SAMPLER,
            image.view,
            sampler.handle,
            vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL,
        );
    }

    /// Points `binding` at a storage image, written in GENERAL layout.
    pub fn write_storage_image(&self, binding: u32, image: &Image) {
        self.write_image(
            binding,
            vk::DescriptorType::STORAGE_IMAGE,
            image.view,
            vk::Sampler::null(),
            vk::ImageLayout::GENERAL,
        );
    }

    /// Points `binding` at one mip level of an image sampled in GENERAL
    /// layout (a level of a chain that compute shaders write and read in
    /// turn).
    pub fn write_sampled_mip(&self, binding: u32, view: &MipView, sampler: &Sampler) {
        self.write_image(
            binding,
            vk::DescriptorType::COMBINED_IMAGE_SAMPLER,
            view.view,
            sampler.handle,
            vk::ImageLayout::GENERAL,
        );
    }

    /// Points `binding` at one mip level of a storage image, read and
    /// written in GENERAL layout.
    pub fn write_storage_mip(&self, binding: u32, view: &MipView) {
        self.write_image(
            binding,
            vk::DescriptorType::STORAGE_IMAGE,
            view.view,
            vk::Sampler::null(),
            vk::ImageLayout::GENERAL,
        );
    }

    /// Points `binding` (of `kind`) at `image_view` with `sampler` (null
    /// for storage images), read in `image_layout`.
    fn write_image(
        &self,
        binding: u32,
        kind: vk::DescriptorType,
        image_view: vk::ImageView,
        sampler: vk::Sampler,
        image_layout: vk::ImageLayout,
    ) {
        let infos = [vk::DescriptorImageInfo {
            sampler,
            image_view,
            image_layout,
        }];
        let write = vk::WriteDescriptorSet::default()
            .dst_set(self.handle)
            .dst_binding(binding)
            .descriptor_type(kind)
            .image_info(&infos);
        // SAFETY: the set is not in use by a pending command buffer; the
        // view and sampler (if any) are alive and match `kind`.
        unsafe { self.ctx.device.update_descriptor_sets(&[write], &[]) };
    }

    /// Points `binding` at an input attachment read in a later subpass (in
    /// the read-only layout the render graph gives input attachments).
    pub fn write_input_attachment(&self, binding: u32, image: &Image) {
        let image_layout = if image.desc.aspect.contains(vk::ImageAspectFlags::DEPTH) {
            vk::ImageLayout::DEPTH_STENCIL_READ_ONLY_OPTIMAL
        } else {
            vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL
        };
        self.write_image(
            binding,
            vk::DescriptorType::INPUT_ATTACHMENT,
            image.view,
            vk::Sampler::null(),
            image_layout,
        );
    }
}
