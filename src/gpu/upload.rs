//! Data uploaded once to device-local memory, through a staging buffer, and made ready for
//! the shaders that read it: the upload is the one place a resource's creation needs a
//! barrier, so it sits above both (memory.rs, barrier.rs).

use super::{barrier, Access, Buffer, BufferDesc, BufferTransition, GpuContext};
use crate::error::Result;
use ash::vk;
use gpu_allocator::MemoryLocation;
use std::sync::Arc;

impl Buffer {
    /// A device-local buffer holding `data`, copied in through a staging buffer once, so
    /// that shaders reading it per fragment or per pixel do not read across the bus on a
    /// discrete GPU. Ready for vertex, index and shader-storage reads when this returns.
    pub fn device_local_with_data<T: bytemuck::Pod>(
        ctx: &Arc<GpuContext>,
        usage: vk::BufferUsageFlags,
        data: &[T],
        name: &str,
    ) -> Result<Self> {
        let staging = Self::with_data(ctx, vk::BufferUsageFlags::TRANSFER_SRC, data, &format!("{name} (staging)"))?;
        let size = staging.size;
        let desc = BufferDesc {
            size,
            usage: usage | vk::BufferUsageFlags::TRANSFER_DST | vk::BufferUsageFlags::SHADER_DEVICE_ADDRESS,
            location: MemoryLocation::GpuOnly,
        };
        let buffer = Self::new(ctx, desc, name)?;
        ctx.submit_and_wait(&format!("uploading {name}"), |cmd| {
            let region = [vk::BufferCopy::default().size(size.max(4))];
            // SAFETY: both buffers hold at least `size` bytes (rounded up to 4 at creation).
            unsafe { ctx.device.cmd_copy_buffer(cmd, staging.raw, buffer.raw, &region) };
            let ready =
                BufferTransition { buffer: &buffer, from: Access::TransferWrite, to: Access::DrawAndComputeRead };
            barrier(ctx, cmd, &[], &[ready]);
            Ok(())
        })?;
        Ok(buffer)
    }
}
