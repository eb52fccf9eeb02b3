//! The compute pass that tests a pinhole reference view's points against every pinhole
//! witness's label image (shaders/stages/witness_mask.comp): what it reads of each witness,
//! its push constants, and its bindings.

use crate::error::Result;
use crate::exact::FACING_TOLERANCE;
use crate::gpu::shaders::{matches_shader_bindings, matches_shader_struct};
use crate::gpu::{Buffer, ComputePipeline, GpuContext, Image, StorageSet};
use crate::render::targets::{ViewKind, ViewTargets};
use crate::sensor::{Intrinsics, PixelRect};
use ash::vk;
use glam::DMat4;
use std::sync::Arc;

/// One witness as the mask reads it (`WitnessData`, std430).
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
pub struct WitnessConstants {
    from_reference: [[f32; 4]; 3],
    centre: [f32; 4],
    intrinsics: [f32; 4],
    band: [u32; 4],
}

matches_shader_struct!(WitnessConstants, WitnessData { from_reference, centre, intrinsics, band });

impl WitnessConstants {
    /// A witness whose pose is reference-from-witness, whose label image has the `drawn`
    /// intrinsics (its `columns` applied) and lies in `band` of the witnesses' attachments.
    /// `None` where a value does not hold in f32.
    pub fn new(pose: DMat4, drawn: &Intrinsics, band: PixelRect) -> Option<Self> {
        let from_reference = pose.inverse();
        let row = |i| from_reference.row(i).as_vec4().to_array();
        let constants = Self {
            from_reference: [row(0), row(1), row(2)],
            centre: pose.w_axis.as_vec4().to_array(),
            intrinsics: [drawn.fx, drawn.fy, drawn.cx, drawn.cy].map(|v| v as f32),
            band: [band.width, band.height, band.row, 0],
        };
        let mut floats =
            constants.from_reference.iter().flatten().chain(&constants.centre).chain(&constants.intrinsics);
        floats.all(|v| v.is_finite()).then_some(constants)
    }
}

/// The mask's push constants (`WitnessMask`, std430).
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
pub struct WitnessMaskConstants {
    intrinsics: [f32; 4],
    region: [u32; 4],
    width: u32,
    witness_count: u32,
    facing_tolerance: f32,
}

matches_shader_struct!(
    WitnessMaskConstants,
    WitnessMask { intrinsics, region, width, witness_count, facing_tolerance }
);

impl WitnessMaskConstants {
    /// Tests the pixels of `region` of a reference view of intrinsics `reference`.
    pub fn new(reference: &Intrinsics, region: PixelRect, witness_count: usize) -> Self {
        Self {
            intrinsics: [reference.fx, reference.fy, reference.cx, reference.cy].map(|v| v as f32),
            region: [region.col, region.row, region.width, region.height],
            width: reference.width,
            witness_count: witness_count as u32,
            facing_tolerance: FACING_TOLERANCE as f32,
        }
    }
}

/// The mask's descriptor set: the reference view's attachments, the witnesses' label images,
/// then the masked labels, each pixel's witness bits and the witnesses' table.
pub struct WitnessMaskBindings {
    set: StorageSet,
}

impl WitnessMaskBindings {
    pub const IMAGES: usize = ViewKind::Range.colour_attachments().len() + ViewKind::Shadow.colour_attachments().len();
    pub const BUFFERS: usize = 3;

    /// `pipeline`: any of the mask's pipelines (their set layouts are defined alike).
    pub fn new(
        ctx: &Arc<GpuContext>,
        pipeline: &ComputePipeline,
        (reference, witnesses): (&ViewTargets, &ViewTargets),
        (masked, lost_by, table): (&Buffer, &Buffer, &Buffer),
    ) -> Result<Self> {
        matches_shader_bindings!(WITNESS_MASK_COMP {
            range_label,
            range_z,
            range_dz_dx,
            range_dz_dy,
            witness_visibility,
            Masked,
            LostBy,
            Witnesses,
        });
        let images: Vec<&Image> = reference.colour.iter().chain(&witnesses.colour).collect();
        let set = StorageSet::new(
            ctx,
            pipeline.set_layout,
            &images,
            (&[], &[masked, lost_by, table]),
            "witness mask bindings",
        )?;
        Ok(Self { set })
    }

    /// Records the label test of `pipeline` over the constants' region (8×8 workgroups).
    pub fn record(&self, cmd: vk::CommandBuffer, pipeline: &ComputePipeline, constants: &WitnessMaskConstants) {
        let groups = [constants.region[2], constants.region[3]].map(|n| n.div_ceil(8));
        self.set.dispatch(cmd, pipeline, bytemuck::bytes_of(constants), groups);
    }
}
