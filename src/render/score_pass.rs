//! The compute pass that accumulates one hypothesis' verification counts
//! (shaders/score.comp, src/verify/counts.rs).

use super::pipelines::Pipelines;
use super::targets::ViewTargets;
use crate::error::Result;
use crate::gpu::{GpuContext, StorageSet};
use ash::vk;
use std::sync::Arc;

/// Push constants of the score pass; matches `shaders/score.comp`.
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
pub struct ScoreConstants {
    pub shadowed_labels: [u32; 2],
    pub sensed_segments: [u32; 2],
    pub sensed_z: [u32; 2],
    pub counts: [u32; 2],
    pub width: u32,
    pub height: u32,
    pub _pad: [u32; 2],
    pub region: [u32; 4],
    pub surfaces: u32,
    pub segments: u32,
    pub tolerance: f32,
    pub area_scale: f32,
    pub dx: f32,
    pub dy: f32,
}

/// The descriptor set binding a range view's label and z attachments for the score pass.
pub struct ScoreBindings {
    set: StorageSet,
}

impl ScoreBindings {
    pub fn new(ctx: &Arc<GpuContext>, pipelines: &Pipelines, range: &ViewTargets) -> Result<Self> {
        Ok(Self {
            set: StorageSet::new(ctx, pipelines.score_set_layout, &[&range.label, &range.z], &[], "score bindings")?,
        })
    }

    pub fn record(&self, ctx: &GpuContext, cmd: vk::CommandBuffer, pipelines: &Pipelines, constants: &ScoreConstants) {
        let d = &ctx.device;
        // SAFETY: cmd is recording; the attachments are in GENERAL layout by now.
        unsafe {
            d.cmd_bind_pipeline(cmd, vk::PipelineBindPoint::COMPUTE, pipelines.score);
            d.cmd_bind_descriptor_sets(
                cmd,
                vk::PipelineBindPoint::COMPUTE,
                pipelines.score_layout,
                0,
                &[self.set.set],
                &[],
            );
            d.cmd_push_constants(
                cmd,
                pipelines.score_layout,
                vk::ShaderStageFlags::COMPUTE,
                0,
                bytemuck::bytes_of(constants),
            );
            d.cmd_dispatch(cmd, constants.region[2].div_ceil(8), constants.region[3].div_ceil(8), 1);
        }
    }
}
