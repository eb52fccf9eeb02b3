//! The compute pass that accumulates one hypothesis' verification counts
//! (shaders/score.comp, src/verify/counts.rs).

use crate::error::Result;
use crate::gpu::{shaders, ComputePipeline, GpuContext, Image, StorageSet};
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
    /// The range view's local origin's z: z = stored offset + z_origin (`ViewGrid::local_origin`).
    pub z_origin: f32,
    pub _pad: u32,
    pub region: [u32; 4],
    pub surfaces: u32,
    pub segments: u32,
    pub tolerance: f32,
    pub area_scale: f32,
    pub dx: f32,
    pub dy: f32,
}

// std430 offsets of `Score` in shaders/score.comp: a uvec4 aligns to 16.
const _: () = assert!(std::mem::offset_of!(ScoreConstants, z_origin) == 40);
const _: () = assert!(std::mem::offset_of!(ScoreConstants, region) == 48);
const _: () = assert!(size_of::<ScoreConstants>() == 88);

/// The score pass's pipeline, built once per verifier.
pub(crate) struct ScorePass {
    pipeline: ComputePipeline,
}

impl ScorePass {
    pub fn new(ctx: &Arc<GpuContext>) -> Result<Self> {
        let bindings = [vk::DescriptorType::STORAGE_IMAGE; 2];
        let pipeline = ComputePipeline::new(
            ctx,
            &bindings,
            size_of::<ScoreConstants>(),
            shaders::SCORE_COMP,
            "verification counts",
        )?;
        Ok(Self { pipeline })
    }

    /// The descriptor set binding a range view's label and z attachments.
    pub fn bindings(&self, ctx: &Arc<GpuContext>, label: &Image, z: &Image) -> Result<ScoreBindings> {
        Ok(ScoreBindings { set: StorageSet::new(ctx, self.pipeline.set_layout, &[label, z], &[], "score bindings")? })
    }
}

pub(crate) struct ScoreBindings {
    set: StorageSet,
}

impl ScoreBindings {
    /// Records the pass over the constants' region (8×8 workgroups).
    pub fn record(&self, cmd: vk::CommandBuffer, pass: &ScorePass, constants: &ScoreConstants) {
        let groups = [constants.region[2], constants.region[3]].map(|n| n.div_ceil(8));
        self.set.dispatch(cmd, &pass.pipeline, bytemuck::bytes_of(constants), groups);
    }
}
