//! The list a depth test's first pass leaves to its second (the scanner's shadow mask,
//! stages/shadow_mask.rs, and a rig's witness mask, pinhole/witness_mask.rs; both shaders'
//! side: shaders/stages/walk_list.glsl): the pixels it
//! could not decide without a walk over the surface, and the second pass's indirect dispatch.
//! A software rasterizer runs a pass's invocations in lockstep, eight at a time, and runs the
//! code of every branch even where none of the eight takes it: walking in place, a pixel a
//! shortcut decided (facing away, off the witness's image, on a hull face) paid for the walk's
//! code all the same. The second pass walks from listed pixels alone.

use crate::error::Result;
use crate::gpu::{Access, Buffer, BufferDesc, GpuContext};
use ash::vk;
use std::sync::Arc;

/// A slot's list: the second pass's dispatch (x, y, z) and the list's length, in a buffer of
/// their own; and room for every pixel of its range view (its index), 4 bytes a pixel, as large
/// as the shadowed labels, which the device binds for any image the renderer accepts
/// (`Renderer::check_pixel_buffers`).
pub struct WalkList {
    pub args: Buffer,
    pub pixels: Buffer,
}

impl WalkList {
    /// The dispatch's arguments and the list's length.
    const ARGS_BYTES: u64 = 16;
    /// A listed pixel's index.
    const BYTES_PER_PIXEL: u64 = 4;
    /// The most workgroups the second pass dispatches (the shaders' MAX_GROUPS); they stride
    /// over a longer list.
    pub const MAX_GROUPS: u32 = 65_535;

    /// Bytes a list for a range view of `pixels` takes (src/render/memory.rs).
    pub fn bytes(pixels: u64) -> u64 {
        Self::ARGS_BYTES + Self::BYTES_PER_PIXEL * pixels
    }

    pub fn new(ctx: &Arc<GpuContext>, pixels: u64, name: &str) -> Result<Self> {
        let args = BufferDesc {
            usage: BufferDesc::gpu_storage(0).usage | vk::BufferUsageFlags::INDIRECT_BUFFER,
            ..BufferDesc::gpu_storage(Self::ARGS_BYTES)
        };
        let list = BufferDesc::gpu_storage(Self::BYTES_PER_PIXEL * pixels);
        Ok(Self {
            args: Buffer::new(ctx, args, &format!("{name} depth test's walks dispatch"))?,
            pixels: Buffer::new(ctx, list, &format!("{name} depth test's walk list"))?,
        })
    }

    /// The use [`WalkList::record_emptying`] makes of the list.
    pub fn emptied(&self) -> (&Buffer, Access) {
        (&self.args, Access::TransferWrite)
    }

    /// The uses the first pass makes of the list, appending to it (in every test: its shader
    /// holds the appending, which a validator takes for a write whatever the test).
    pub fn appended(&self) -> [(&Buffer, Access); 2] {
        [(&self.args, Access::ComputeWrite), (&self.pixels, Access::ComputeWrite)]
    }

    /// The uses the second pass makes of the list: its dispatch, and the pixels it reads.
    pub fn walked(&self) -> [(&Buffer, Access); 2] {
        [(&self.args, Access::IndirectAndComputeRead), (&self.pixels, Access::ComputeRead)]
    }

    /// Records the list's emptying, before the first pass: no workgroups, no entries (x, y,
    /// z, length).
    pub fn record_emptying(&self, ctx: &GpuContext, cmd: vk::CommandBuffer) {
        // SAFETY: cmd is recording; the step's barrier ordered earlier uses of the buffer; the
        // update fills it.
        unsafe { ctx.device.cmd_update_buffer(cmd, self.args.raw, 0, bytemuck::cast_slice(&[0u32, 1, 1, 0])) };
    }
}
