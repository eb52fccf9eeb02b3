//! Barriers derived from declared access (after kajiya's render graph): an [`Encoder`] knows
//! the current use of every resource it has seen in one command buffer, and a pass states
//! only the use it needs next. The encoder issues the transitions that takes, all in one
//! barrier, and none where a read follows a read in the same layout. No call site tracks a
//! "from" state.
//!
//! Every resource starts a command buffer as [`Access::Nothing`]: a render target's earlier
//! contents are discarded (each job clears and draws the pixels it reads), and buffers the
//! host wrote, or an earlier submission left ready, are visible to a new submission without a
//! barrier (the queue submission orders them).

use super::barrier::{barrier, Access, BufferTransition, ImageTransition};
use super::memory::{Buffer, Image};
use super::GpuContext;
use ash::vk::{self, Handle};
use std::collections::HashMap;

pub struct Encoder<'a> {
    ctx: &'a GpuContext,
    pub cmd: vk::CommandBuffer,
    /// By object type and handle: handles of different types may coincide.
    current: HashMap<(vk::ObjectType, u64), Access>,
}

impl<'a> Encoder<'a> {
    pub fn new(ctx: &'a GpuContext, cmd: vk::CommandBuffer) -> Self {
        Self { ctx, cmd, current: HashMap::new() }
    }

    pub fn ctx(&self) -> &'a GpuContext {
        self.ctx
    }

    /// Makes each image and buffer ready for its next use, recording one barrier for all.
    pub fn access(&mut self, images: &[(&Image, Access)], buffers: &[(&Buffer, Access)]) {
        let mut image_transitions = Vec::new();
        for &(image, to) in images {
            if let Some(from) = self.transition((vk::ObjectType::IMAGE, image.raw.as_raw()), to) {
                image_transitions.push(ImageTransition { image, from, to });
            }
        }
        let mut buffer_transitions = Vec::new();
        for &(buffer, to) in buffers {
            if let Some(from) = self.transition((vk::ObjectType::BUFFER, buffer.raw.as_raw()), to) {
                buffer_transitions.push(BufferTransition { buffer, from, to });
            }
        }
        if !(image_transitions.is_empty() && buffer_transitions.is_empty()) {
            barrier(self.ctx, self.cmd, &image_transitions, &buffer_transitions);
        }
    }

    /// The use a resource moves from, or `None` when no barrier is needed: a read after the
    /// same read (same stages, same layout).
    fn transition(&mut self, handle: (vk::ObjectType, u64), to: Access) -> Option<Access> {
        let from = self.current.insert(handle, to).unwrap_or(Access::Nothing);
        (!(from == to && to.is_read_only())).then_some(from)
    }
}
