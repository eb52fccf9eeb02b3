//! The compute pass that applies the shadow test (shaders/stages/shadow_mask.comp, src/shadow.rs)
//! to the range view, reading both views' attachments and writing the shadowed labels.
//!
//! Where the compute rasterizer rendered the views (raster/compute/), its variant reads
//! their visibility words instead, so that neither view takes a resolve pass of its own: it
//! reads the shadow view's words where the other reads the visibility attachment, and it
//! resolves the range view itself, writing the range view's attachments from its words as the
//! resolve pass would and testing what it wrote. A resolve pass is a large share of a small
//! model's time on lavapipe, and resolving in the mask costs less than a pass of its own
//! (docs/compute-rasterizer.md). Where no pass after it reads the range view's label or
//! gradient, a variant writes only its z ([`MaskVariant::WordsForScoring`]), saving those
//! stores.
//!
//! The variants reading words take the depth test in two passes: the first decides each pixel
//! it can without a walk over the surface (facing away, outside the shadow view, on a hull
//! face) and lists the others in a [`WalkList`] (which says why); the second, an indirect
//! dispatch of a shader variant of its own, walks from the listed pixels only. (Views of
//! several draws, which the mask reads from their attachments, walk in place.)

use crate::error::Result;
use crate::gpu::shaders::layout::spec::SHADOW_MASK_COMP as spec;
use crate::gpu::shaders::{matches_shader_bindings, matches_shader_struct};
use crate::gpu::{shaders, Buffer, ComputePipeline, GpuContext, Image, SetShape, StorageSet};
use crate::mesh::{LINK_EDGE_MASK, LINK_INDEX_SHIFT, LINK_SAME_WAY};
use crate::render::gpu_mesh::HullFaces;
use crate::render::plan::Views;
use crate::render::stages::mask_pipelines::MaskPipelines;
use crate::render::stages::walk_list::WalkList;
use crate::render::targets::{ViewKind, ViewTargets};
use crate::sensor::{PixelRect, Scanner, ViewGrid};
use crate::shadow::{ShadowTest, DEPTH_BIAS_PIXELS, DEPTH_BIAS_RELATIVE};
use ash::vk;
use glam::DVec3;
use std::sync::Arc;

/// Push constants of the mask pass; matches `shaders/stages/shadow_mask.comp`.
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
    hull_faces: [u32; 2],
    words_draw: u32,
    shadow_stride: u32,
    range_stride: u32,
    hull_tolerance: f32,
}

// std430 offsets of `Mask` in shaders/stages/shadow_mask.comp.
matches_shader_struct!(
    MaskConstants,
    Mask {
        range_grid,
        shadow_grid,
        sizes,
        region,
        cos_theta,
        sin_theta,
        bias_pitch,
        bias_relative,
        hull_faces,
        words_draw,
        shadow_stride,
        range_stride,
        hull_tolerance,
    }
);

impl MaskConstants {
    /// Constants for masking the range pixels of `region`. Both grids are given from the
    /// views' local origin, as the views were rendered (draw.rs).
    pub fn new(sensor: &Scanner, views: &Views, shadow: &ViewGrid, region: PixelRect) -> Self {
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
            hull_faces: [0; 2],
            words_draw: 0,
            shadow_stride: 0,
            range_stride: 0,
            hull_tolerance: 0.0,
        }
    }

    /// The same constants for the pipelines reading both views from visibility words, the
    /// range view's `range_stride` pixels a row and the shadow view's `shadow_stride`, which
    /// rendered draw `draw` alone: where given its mesh's `hull` faces (`GpuMesh::hull_faces`,
    /// the depth test's), the depth test skips its walks from them, which nothing else in the
    /// views can hide.
    pub fn reading_words(self, draw: u32, hull: Option<&HullFaces>, (range_stride, shadow_stride): (u32, u32)) -> Self {
        Self {
            hull_faces: hull.map_or([0; 2], |hull| hull.bits.address_words()),
            words_draw: draw,
            shadow_stride,
            range_stride,
            hull_tolerance: hull.map_or(0.0, |hull| hull.tolerance),
            ..self
        }
    }
}

/// What a mask pipeline reads the views from, and what it writes of the range view.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub enum MaskVariant {
    /// The views' attachments, which the graphics pipeline rendered.
    Attachments,
    /// The compute rasterizer's words; it writes the range view's attachments whole.
    Words,
    /// The compute rasterizer's words, for passes after it that read only the range view's z
    /// (a score pass of the shadowed labels): it writes no label or gradient there.
    WordsForScoring,
}

/// The mask pipelines of one [`MaskVariant`] (mask_pipelines.rs), with the depth test's
/// second pass (the shader's variant WALKS_FROM_LIST) for the variants reading words.
pub fn mask_pipelines(ctx: &Arc<GpuContext>, variant: MaskVariant) -> Result<MaskPipelines> {
    let (code, source) = match variant {
        MaskVariant::Attachments => (shaders::SHADOW_MASK_COMP, ""),
        MaskVariant::Words => (shaders::SHADOW_MASK_WORDS_COMP, ", from visibility words"),
        MaskVariant::WordsForScoring => (shaders::SHADOW_MASK_WORDS_COMP, ", from visibility words, for scoring"),
    };
    let write_label_and_gradient = u32::from(variant != MaskVariant::WordsForScoring);
    let walks = (variant != MaskVariant::Attachments).then_some(shaders::SHADOW_MASK_WALKS_COMP);
    MaskPipelines::new(code, walks, |code, test, name| {
        ComputePipeline::new(
            ctx,
            SetShape::storage(MaskBindings::IMAGES, MaskBindings::BUFFERS),
            size_of::<MaskConstants>(),
            code,
            &[
                (spec::TEST, test as u32),
                (spec::TEST_LABEL, ShadowTest::Label as u32),
                (spec::TEST_LABEL_SQUARE, ShadowTest::LabelSquare as u32),
                (spec::LINK_INDEX_SHIFT, LINK_INDEX_SHIFT),
                (spec::LINK_SAME_WAY, LINK_SAME_WAY),
                (spec::LINK_EDGE_MASK, LINK_EDGE_MASK),
                (spec::WRITE_LABEL_AND_GRADIENT, write_label_and_gradient),
                (spec::MAX_GROUPS, WalkList::MAX_GROUPS),
            ],
            &format!("shadow mask ({name}){source}"),
        )
    })
}

/// What the variant reading visibility words reads besides the shadow view's draw table: the
/// shadow view's words, the range view's draw table and the range view's words.
pub struct WordsToMask<'a> {
    pub shadow_words: &'a Buffer,
    pub range_table: &'a Buffer,
    pub range_words: &'a Buffer,
}

/// The descriptor set binding both views' colour attachments (range view's, then shadow
/// view's), the output labels, the shadow view's draw table and what the variant reading
/// visibility words reads and writes (the draw table again where there are none: never read
/// then).
pub struct MaskBindings {
    set: StorageSet,
}

impl MaskBindings {
    /// Storage images the mask pass binds, from binding 0.
    pub const IMAGES: usize = ViewKind::Range.colour_attachments().len() + ViewKind::Shadow.colour_attachments().len();
    /// Storage buffers bound after them: the shadowed labels, the draw table,
    /// [`WordsToMask`]'s three and the [`WalkList`]'s two.
    pub const BUFFERS: usize = 7;

    /// `draw_table` holds the shadow pass's [`DrawConstants`](crate::render::raster::draw::DrawConstants)
    /// at the draw indices it recorded.
    pub fn new(
        ctx: &Arc<GpuContext>,
        pipelines: &MaskPipelines,
        range: &ViewTargets,
        shadow: &ViewTargets,
        masked: &Buffer,
        draw_table: &Buffer,
        words: Option<(&WordsToMask, &WalkList)>,
    ) -> Result<Self> {
        let images: Vec<&Image> = range.colour.iter().chain(&shadow.colour).collect();
        debug_assert_eq!(images.len(), Self::IMAGES);
        let buffers = match words {
            Some((w, walks)) => {
                [masked, draw_table, w.shadow_words, w.range_table, w.range_words, &walks.args, &walks.pixels]
            }
            None => [masked, draw_table, draw_table, draw_table, draw_table, draw_table, draw_table],
        };
        matches_shader_bindings!([SHADOW_MASK_COMP, SHADOW_MASK_WORDS_COMP, SHADOW_MASK_WALKS_COMP] {
            range_label,
            range_z,
            range_dz_dx,
            range_dz_dy,
            shadow_visibility,
            Masked,
            DrawTable,
            ShadowWords,
            RangeDrawTable,
            RangeWords,
            WalkArgs,
            WalkPixels,
        });
        let set_layout = pipelines.for_test(ShadowTest::Label).set_layout;
        Ok(Self { set: StorageSet::new(ctx, set_layout, &images, (&[], &buffers), "shadow mask bindings")? })
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

    /// Records the depth test's second pass, `walks` ([`MaskPipelines::second_pass`]), over the
    /// pixels the first listed in `list`.
    pub fn record_walks(
        &self,
        cmd: vk::CommandBuffer,
        walks: &ComputePipeline,
        list: &WalkList,
        constants: &MaskConstants,
    ) {
        self.set.dispatch_indirect(cmd, walks, bytemuck::bytes_of(constants), &list.args);
    }
}
