//! The list a depth test's first pass leaves to its second (the scanner's shadow mask,
//! stages/shadow_mask.rs, and a rig's witness mask, pinhole/witness_mask.rs): the pixels it
//! could not decide without a walk over the surface, and the second pass's indirect dispatch.
//! A software rasterizer runs a pass's invocations in lockstep, eight at a time, and runs the
//! code of every branch even where none of the eight takes it: walking in place, a pixel a
//! shortcut decided (facing away, off the witness's image, on a hull face) paid for the walk's
//! code all the same. The second pass walks from listed pixels alone.

use crate::error::Result;
use crate::gpu::{Buffer, BufferDesc, GpuContext};
use ash::vk;
use std::sync::Arc;

/// What an entry of a list holds (the shaders' `WalkList`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum WalkEntry {
    /// A range pixel's index (the scanner's one witness).
    Pixel,
    /// A range pixel's index and the bits of the witnesses to walk toward (a rig's).
    PixelAndWitnesses,
}

impl WalkEntry {
    fn bytes(self) -> u64 {
        match self {
            WalkEntry::Pixel => 4,
            WalkEntry::PixelAndWitnesses => 8,
        }
    }
}

/// A slot's list, with room for an entry for every pixel of its range view, after the second
/// pass's dispatch (x, y, z) and the list's length.
pub struct WalkList {
    pub buffer: Buffer,
}

impl WalkList {
    /// The dispatch's arguments and the list's length, before the entries.
    const HEADER_BYTES: u64 = 16;
    /// The most workgroups the second pass dispatches (the shaders' MAX_GROUPS); they stride
    /// over a longer list.
    pub const MAX_GROUPS: u32 = 65_535;

    /// Bytes a list for a range view of `pixels` takes (src/render/memory.rs).
    pub fn bytes(pixels: u64, entry: WalkEntry) -> u64 {
        Self::HEADER_BYTES + entry.bytes() * pixels
    }

    pub fn new(ctx: &Arc<GpuContext>, pixels: u64, entry: WalkEntry, name: &str) -> Result<Self> {
        let desc = BufferDesc {
            usage: BufferDesc::gpu_storage(0).usage | vk::BufferUsageFlags::INDIRECT_BUFFER,
            ..BufferDesc::gpu_storage(Self::bytes(pixels, entry))
        };
        Ok(Self { buffer: Buffer::new(ctx, desc, &format!("{name} depth test's walk list"))? })
    }

    /// Records the list's emptying, before the first pass: no workgroups, no entries (x, y,
    /// z, length). A transfer write.
    pub fn record_emptying(&self, ctx: &GpuContext, cmd: vk::CommandBuffer) {
        // SAFETY: cmd is recording; the step's barrier ordered earlier uses of the buffer; the
        // update fits its header.
        unsafe { ctx.device.cmd_update_buffer(cmd, self.buffer.raw, 0, bytemuck::cast_slice(&[0u32, 1, 1, 0])) };
    }
}
