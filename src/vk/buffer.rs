//! Buffers with gpu-allocator memory.

use super::{Context, VkError};
use ash::vk;
use gpu_allocator::vulkan::{Allocation, AllocationCreateDesc, AllocationScheme};
use gpu_allocator::MemoryLocation;
use std::sync::Arc;

/// What a buffer is for; decides usage flags and memory location.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BufferUsage {
    /// Vertex and index data, written once from the CPU.
    Geometry,
    /// Uniform data written from the CPU.
    Uniform,
    /// Per-instance vertex data, written from the CPU when the view
    /// changes.
    Instances,
    /// Staging for uploads to images.
    Upload,
    /// Destination of image copies, read back on the CPU.
    Readback,
    /// Read, or written and read, by shaders (a value one pass computes
    /// for another; the shadow block, see `shadow_map.glsl`).
    Storage,
}

impl BufferUsage {
    fn flags(self) -> vk::BufferUsageFlags {
        match self {
            BufferUsage::Geometry => {
                vk::BufferUsageFlags::VERTEX_BUFFER | vk::BufferUsageFlags::INDEX_BUFFER
            }
            BufferUsage::Uniform => vk::BufferUsageFlags::UNIFORM_BUFFER,
            BufferUsage::Instances => vk::BufferUsageFlags::VERTEX_BUFFER,
            BufferUsage::Upload => vk::BufferUsageFlags::TRANSFER_SRC,
            BufferUsage::Readback => vk::BufferUsageFlags::TRANSFER_DST,
            BufferUsage::Storage => vk::BufferUsageFlags::STORAGE_BUFFER,
        }
    }

    fn location(self) -> MemoryLocation {
        match self {
            BufferUsage::Readback => MemoryLocation::GpuToCpu,
            // Small, written once per run; host-visible memory avoids a
            // staging copy (and on unified-memory devices it is the same).
            _ => MemoryLocation::CpuToGpu,
        }
    }
}

/// A buffer and its memory; host-visible, so it can be written or read
/// directly.
pub struct Buffer {
    ctx: Arc<Context>,
    pub(crate) handle: vk::Buffer,
    allocation: Option<Allocation>,
    size: u64,
}

impl Buffer {
    pub fn new(
        ctx: &Arc<Context>,
        name: &str,
        size: u64,
        usage: BufferUsage,
    ) -> Result<Buffer, VkError> {
        let size = size.max(4);
        let info = vk::BufferCreateInfo::default()
            .size(size)
            .usage(usage.flags())
            .sharing_mode(vk::SharingMode::EXCLUSIVE);
        // SAFETY: valid device and create info.
        let handle = unsafe { ctx.device.create_buffer(&info, None) }?;
        // SAFETY: handle was just created on this device.
        let requirements = unsafe { ctx.device.get_buffer_memory_requirements(handle) };
        let allocation = ctx.allocator().allocate(&AllocationCreateDesc {
            name,
            requirements,
            location: usage.location(),
            linear: true,
            allocation_scheme: AllocationScheme::GpuAllocatorManaged,
        });
        let allocation = match allocation {
            Ok(a) => a,
            Err(e) => {
                // SAFETY: unbound buffer not used by anything.
                unsafe { ctx.device.destroy_buffer(handle, None) };
                return Err(e.into());
            }
        };
        // SAFETY: memory satisfies the buffer's requirements; bound once.
        let bound = unsafe {
            ctx.device
                .bind_buffer_memory(handle, allocation.memory(), allocation.offset())
        };
        let buffer = Buffer {
            ctx: ctx.clone(),
            handle,
            allocation: Some(allocation),
            size,
        };
        bound?;
        Ok(buffer)
    }

    /// A buffer created and filled with `data`.
    pub fn with_data(
        ctx: &Arc<Context>,
        name: &str,
        data: &[u8],
        usage: BufferUsage,
    ) -> Result<Buffer, VkError> {
        let mut buffer = Buffer::new(ctx, name, data.len() as u64, usage)?;
        buffer.write(0, data);
        Ok(buffer)
    }

    pub fn size(&self) -> u64 {
        self.size
    }

    /// Copies `data` into the mapped memory at `offset`.
    ///
    /// Panics if the range is outside the buffer: that is a bug in the
    /// caller, never a consequence of user input.
    pub fn write(&mut self, offset: usize, data: &[u8]) {
        let slice = self
            .allocation
            .as_mut()
            .and_then(|a| a.mapped_slice_mut())
            .expect("host-visible buffers are persistently mapped");
        slice[offset..offset + data.len()].copy_from_slice(data);
    }

    /// The mapped contents (after the GPU finished writing them).
    pub fn read(&self) -> &[u8] {
        let slice = self
            .allocation
            .as_ref()
            .and_then(|a| a.mapped_slice())
            .expect("host-visible buffers are persistently mapped");
        &slice[..self.size as usize]
    }
}

impl Drop for Buffer {
    fn drop(&mut self) {
        // SAFETY: the owner waits for the GPU to finish with the buffer before
        // dropping it (renders end with a fence wait).
        unsafe { self.ctx.device.destroy_buffer(self.handle, None) };
        if let Some(a) = self.allocation.take() {
            let _ = self.ctx.allocator().free(a);
        }
    }
}
