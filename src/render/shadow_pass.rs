//! The compute pass that applies the shadow test (shaders/shadow_mask.comp, src/shadow.rs)
//! to the range view, reading both views' attachments and writing the shadowed labels.

use super::pipelines::Pipelines;
use super::targets::{ViewKind, ViewTargets};
use super::Views;
use crate::error::Result;
use crate::gpu::{shaders, Buffer, ComputePipeline, GpuContext, Image, StorageSet};
use crate::mesh::{LINK_EDGE_MASK, LINK_INDEX_SHIFT, LINK_SAME_WAY};
use crate::sensor::{PixelRect, Sensor, ViewGrid};
use crate::shadow::{ShadowTest, DEPTH_BIAS_PIXELS, DEPTH_BIAS_RELATIVE};
use ash::vk;
use glam::DVec3;
use std::sync::Arc;

/// Push constants of the mask pass; matches `shaders/shadow_mask.comp`.
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
pub struct MaskConstants {
    range_grid: [f32; 4],
    shadow_grid: [f32; 4],
    sizes: [i32; 4],
    region: [i32; 4],
    cos_theta: f32,
    sin_theta: f32,
    bias_pitch: f32,
    bias_relative: f32,
}

// std430 offsets of `Mask` in shaders/shadow_mask.comp.
const _: () = assert!(std::mem::offset_of!(MaskConstants, cos_theta) == 64);
const _: () = assert!(size_of::<MaskConstants>() == 80);

impl MaskConstants {
    /// Constants for masking the range pixels of `region`. Both grids are given from the
    /// views' local origin, as the views were rendered (draw.rs).
    pub fn new(sensor: &Sensor, views: &Views, shadow: &ViewGrid, region: PixelRect) -> Self {
        let range = &views.range;
        let grid = |g: &ViewGrid, origin: DVec3| {
            [g.origin[0] - origin.x, g.origin[1] - origin.y, g.pitch[0], g.pitch[1]].map(|v| v as f32)
        };
        Self {
            range_grid: grid(range, views.origin),
            shadow_grid: grid(shadow, sensor.to_shadow_frame().transform_point3(views.origin)),
            sizes: [range.width as i32, range.height as i32, shadow.width as i32, shadow.height as i32],
            region: [region.col, region.row, region.width, region.height].map(|v| v as i32),
            cos_theta: sensor.theta().cos() as f32,
            sin_theta: sensor.theta().sin() as f32,
            bias_pitch: (DEPTH_BIAS_PIXELS * sensor.pitch[0]) as f32,
            bias_relative: DEPTH_BIAS_RELATIVE as f32,
        }
    }
}

/// The mask pipelines, one per [`ShadowTest`], the test a specialization constant. Their
/// descriptor-set layouts are defined identically, so one set serves all three. On lavapipe,
/// which runs both sides of a branch on a uniform value, the label test alone ran in a
/// quarter of the time of the shader that switched on a push constant (256², 1.0 ms
/// against 4.5 ms).
pub struct MaskPipelines {
    label: ComputePipeline,
    label_square: ComputePipeline,
    depth: ComputePipeline,
}

impl MaskPipelines {
    pub fn new(ctx: &Arc<GpuContext>) -> Result<Self> {
        let pipeline = |test: ShadowTest, name: &str| {
            ComputePipeline::new(
                ctx,
                (MaskBindings::IMAGES, MaskBindings::BUFFERS),
                size_of::<MaskConstants>(),
                shaders::SHADOW_MASK_COMP,
                &[
                    test as u32,
                    ShadowTest::Label as u32,
                    ShadowTest::LabelSquare as u32,
                    LINK_INDEX_SHIFT,
                    LINK_SAME_WAY,
                    LINK_EDGE_MASK,
                ],
                name,
            )
        };
        Ok(Self {
            label: pipeline(ShadowTest::Label, "shadow mask (label test)")?,
            label_square: pipeline(ShadowTest::LabelSquare, "shadow mask (2x2 label test)")?,
            depth: pipeline(ShadowTest::Depth, "shadow mask (depth test)")?,
        })
    }

    pub fn for_test(&self, test: ShadowTest) -> &ComputePipeline {
        match test {
            ShadowTest::Label => &self.label,
            ShadowTest::LabelSquare => &self.label_square,
            ShadowTest::Depth => &self.depth,
        }
    }
}

/// The descriptor set binding both views' colour attachments (range view's, then shadow
/// view's), the output labels and the shadow view's draw table.
pub struct MaskBindings {
    set: StorageSet,
}

impl MaskBindings {
    /// Storage images the mask pass binds, from binding 0.
    pub const IMAGES: usize = ViewKind::Range.colour_attachments().len() + ViewKind::Shadow.colour_attachments().len();
    /// Storage buffers bound after them: the shadowed labels and the draw table.
    pub const BUFFERS: usize = 2;

    /// `draw_table` holds the shadow pass's [`DrawConstants`](super::draw::DrawConstants)
    /// at the draw indices it recorded.
    pub fn new(
        ctx: &Arc<GpuContext>,
        pipelines: &Pipelines,
        range: &ViewTargets,
        shadow: &ViewTargets,
        masked: &Buffer,
        draw_table: &Buffer,
    ) -> Result<Self> {
        let images: Vec<&Image> = range.colour.iter().chain(&shadow.colour).collect();
        debug_assert_eq!(images.len(), Self::IMAGES);
        let buffers = [masked, draw_table];
        let set_layout = pipelines.mask.for_test(ShadowTest::Label).set_layout;
        Ok(Self { set: StorageSet::new(ctx, set_layout, &images, &buffers, "shadow mask bindings")? })
    }

    /// Records `test` over the constants' region (8×8 workgroups).
    pub fn record(&self, cmd: vk::CommandBuffer, pipelines: &Pipelines, test: ShadowTest, constants: &MaskConstants) {
        let groups = [constants.region[2] as u32, constants.region[3] as u32].map(|n| n.div_ceil(8));
        self.set.dispatch(cmd, pipelines.mask.for_test(test), bytemuck::bytes_of(constants), groups);
    }
}
