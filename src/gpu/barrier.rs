//! Barriers as data (after kajiya's `barrier.rs`): a pass declares how it uses a resource,
//! one table turns that use into stage, access and layout, and one call issues every
//! transition at once with `vkCmdPipelineBarrier2`.

use super::memory::{subresource_range, Buffer, Image};
use super::GpuContext;
use ash::vk;

/// How a pass uses a resource.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Access {
    /// Contents are not needed (first use).
    Nothing,
    ColorAttachmentWrite,
    DepthAttachmentWrite,
    /// Read in a compute shader as a storage image or storage buffer.
    ComputeRead,
    /// Written (or atomically updated) in a compute shader.
    ComputeWrite,
    /// Read in a compute shader as a uniform buffer.
    UniformRead,
    TransferRead,
    TransferWrite,
    /// Mapped memory read by the host after the fence.
    HostRead,
    /// Read as vertex or index data, or as storage by any shader: a mesh or an input image.
    DrawAndComputeRead,
    /// Read as a dispatch's indirect arguments, or as storage by a compute shader.
    IndirectAndComputeRead,
}

impl Access {
    /// Whether the use only reads, so that the same use again needs no barrier.
    pub fn is_read_only(self) -> bool {
        matches!(
            self,
            Access::ComputeRead
                | Access::UniformRead
                | Access::TransferRead
                | Access::HostRead
                | Access::DrawAndComputeRead
                | Access::IndirectAndComputeRead
        )
    }
}

/// (stage, access, image layout) of each use.
fn describe(access: Access) -> (vk::PipelineStageFlags2, vk::AccessFlags2, vk::ImageLayout) {
    use vk::{AccessFlags2 as A, ImageLayout as L, PipelineStageFlags2 as S};
    match access {
        Access::Nothing => (S::NONE, A::NONE, L::UNDEFINED),
        Access::ColorAttachmentWrite => {
            (S::COLOR_ATTACHMENT_OUTPUT, A::COLOR_ATTACHMENT_WRITE, L::COLOR_ATTACHMENT_OPTIMAL)
        }
        Access::DepthAttachmentWrite => (
            S::EARLY_FRAGMENT_TESTS | S::LATE_FRAGMENT_TESTS,
            A::DEPTH_STENCIL_ATTACHMENT_READ | A::DEPTH_STENCIL_ATTACHMENT_WRITE,
            L::DEPTH_ATTACHMENT_OPTIMAL,
        ),
        Access::ComputeRead => (S::COMPUTE_SHADER, A::SHADER_STORAGE_READ, L::GENERAL),
        Access::ComputeWrite => (S::COMPUTE_SHADER, A::SHADER_STORAGE_READ | A::SHADER_STORAGE_WRITE, L::GENERAL),
        Access::UniformRead => (S::COMPUTE_SHADER, A::UNIFORM_READ, L::GENERAL),
        Access::TransferRead => (S::COPY, A::TRANSFER_READ, L::TRANSFER_SRC_OPTIMAL),
        Access::TransferWrite => (S::COPY | S::CLEAR, A::TRANSFER_WRITE, L::TRANSFER_DST_OPTIMAL),
        Access::HostRead => (S::HOST, A::HOST_READ, L::GENERAL),
        Access::DrawAndComputeRead => (
            S::VERTEX_ATTRIBUTE_INPUT | S::INDEX_INPUT | S::VERTEX_SHADER | S::FRAGMENT_SHADER | S::COMPUTE_SHADER,
            A::VERTEX_ATTRIBUTE_READ | A::INDEX_READ | A::SHADER_STORAGE_READ,
            L::GENERAL,
        ),
        Access::IndirectAndComputeRead => {
            (S::DRAW_INDIRECT | S::COMPUTE_SHADER, A::INDIRECT_COMMAND_READ | A::SHADER_STORAGE_READ, L::GENERAL)
        }
    }
}

pub struct ImageTransition<'a> {
    pub image: &'a Image,
    pub from: Access,
    pub to: Access,
}

pub struct BufferTransition<'a> {
    pub buffer: &'a Buffer,
    pub from: Access,
    pub to: Access,
}

/// Issues all transitions in one `vkCmdPipelineBarrier2`.
pub fn barrier(ctx: &GpuContext, cmd: vk::CommandBuffer, images: &[ImageTransition], buffers: &[BufferTransition]) {
    let image_barriers: Vec<_> = images
        .iter()
        .map(|t| {
            let (src_stage, src_access, old_layout) = describe(t.from);
            let (dst_stage, dst_access, new_layout) = describe(t.to);
            vk::ImageMemoryBarrier2::default()
                .src_stage_mask(src_stage)
                .src_access_mask(src_access)
                .dst_stage_mask(dst_stage)
                .dst_access_mask(dst_access)
                .old_layout(old_layout)
                .new_layout(new_layout)
                .image(t.image.raw)
                .subresource_range(subresource_range(t.image.desc.aspect()))
        })
        .collect();
    let buffer_barriers: Vec<_> = buffers
        .iter()
        .map(|t| {
            let (src_stage, src_access, _) = describe(t.from);
            let (dst_stage, dst_access, _) = describe(t.to);
            vk::BufferMemoryBarrier2::default()
                .src_stage_mask(src_stage)
                .src_access_mask(src_access)
                .dst_stage_mask(dst_stage)
                .dst_access_mask(dst_access)
                .buffer(t.buffer.raw)
                .size(vk::WHOLE_SIZE)
        })
        .collect();
    let info =
        vk::DependencyInfo::default().image_memory_barriers(&image_barriers).buffer_memory_barriers(&buffer_barriers);
    // SAFETY: cmd is recording; every handle is alive for the command buffer's lifetime.
    unsafe { ctx.cmd_pipeline_barrier2(cmd, &info) };
}
