//! The compute pass that applies the shadow test (shaders/shadow_mask.comp, src/shadow.rs)
//! to the range view, reading both views' attachments and writing the shadowed labels. Where
//! the compute rasterizer rendered the shadow view, the pass reads its visibility words
//! instead of the visibility attachment, so that view needs no resolve pass (compute_raster.rs;
//! it cost about 0.9 ms of the box's 3.7 ms a hypothesis in label mode on lavapipe).

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
    words_draw: u32,
    words_stride: u32,
}

// std430 offsets of `Mask` in shaders/shadow_mask.comp.
const _: () = assert!(std::mem::offset_of!(MaskConstants, cos_theta) == 64);
const _: () = assert!(std::mem::offset_of!(MaskConstants, words_draw) == 80);
const _: () = assert!(size_of::<MaskConstants>() == 88);

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
            words_draw: 0,
            words_stride: 0,
        }
    }

    /// The same constants for a pipeline reading the shadow view from visibility words
    /// `stride` pixels a row, rendered for draw `draw` alone.
    pub fn reading_words(self, draw: u32, stride: u32) -> Self {
        Self { words_draw: draw, words_stride: stride, ..self }
    }
}

/// The mask pipelines, one per [`ShadowTest`], the test a specialization constant, and
/// another the shadow view's source (the visibility attachment, or the compute rasterizer's
/// words). Their descriptor-set layouts are defined identically, so one set serves them all.
/// On lavapipe, which runs both sides of a branch on a uniform value, the label test alone ran
/// in a quarter of the time of the shader that switched on a push constant (256², 1.0 ms
/// against 4.5 ms).
pub struct MaskPipelines {
    label: ComputePipeline,
    label_square: ComputePipeline,
    depth: ComputePipeline,
}

impl MaskPipelines {
    /// The pipelines reading the shadow view from the visibility attachment, or, `from_words`,
    /// from the compute rasterizer's words.
    pub fn new(ctx: &Arc<GpuContext>, from_words: bool) -> Result<Self> {
        let source = if from_words { ", from visibility words" } else { "" };
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
                    u32::from(from_words),
                ],
                &format!("{name}{source}"),
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
/// view's), the output labels, the shadow view's draw table and the compute rasterizer's
/// shadow-view words (the draw table again where there are none: never read then).
pub struct MaskBindings {
    set: StorageSet,
}

impl MaskBindings {
    /// Storage images the mask pass binds, from binding 0.
    pub const IMAGES: usize = ViewKind::Range.colour_attachments().len() + ViewKind::Shadow.colour_attachments().len();
    /// Storage buffers bound after them: the shadowed labels, the draw table and the words.
    pub const BUFFERS: usize = 3;

    /// `draw_table` holds the shadow pass's [`DrawConstants`](super::draw::DrawConstants)
    /// at the draw indices it recorded.
    pub fn new(
        ctx: &Arc<GpuContext>,
        pipelines: &Pipelines,
        range: &ViewTargets,
        shadow: &ViewTargets,
        masked: &Buffer,
        draw_table: &Buffer,
        shadow_words: Option<&Buffer>,
    ) -> Result<Self> {
        let images: Vec<&Image> = range.colour.iter().chain(&shadow.colour).collect();
        debug_assert_eq!(images.len(), Self::IMAGES);
        let buffers = [masked, draw_table, shadow_words.unwrap_or(draw_table)];
        let set_layout = pipelines.mask.for_test(ShadowTest::Label).set_layout;
        Ok(Self { set: StorageSet::new(ctx, set_layout, &images, &buffers, "shadow mask bindings")? })
    }

    /// Records `test` with one of `pipelines` over the constants' region (8×8 workgroups).
    pub fn record(
        &self,
        cmd: vk::CommandBuffer,
        pipelines: &MaskPipelines,
        test: ShadowTest,
        constants: &MaskConstants,
    ) {
        let groups = [constants.region[2] as u32, constants.region[3] as u32].map(|n| n.div_ceil(8));
        self.set.dispatch(cmd, pipelines.for_test(test), bytemuck::bytes_of(constants), groups);
    }
}
