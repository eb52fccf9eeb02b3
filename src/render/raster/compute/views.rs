//! One slot's visibility words, which coverage fills, and the passes that resolve them into
//! the views' attachments.

use super::layout::{RasterView, VISIBILITY_WORD_BYTES};
use super::pipelines::ComputeRasterPipelines;
use crate::error::Result;
use crate::gpu::shaders::matches_shader_bindings;
use crate::gpu::{Access, Buffer, BufferDesc, ComputePipeline, GpuContext, Image, Step, StorageSet};
use crate::render::raster::draw::DrawTable;
use crate::render::stages::shadow_mask::WordsToMask;
use crate::render::targets::{ViewKind, ViewTargets};
use crate::sensor::PixelRect;
use std::sync::Arc;

/// A view the compute rasterizer renders: its attachments' size, and its draw table.
pub(crate) struct ComputeTarget<'a> {
    pub size: (u32, u32),
    pub draw_table: &'a DrawTable,
}

/// One view's visibility words.
pub(super) struct ViewWords<'a> {
    pub(super) nearest: Buffer,
    /// Pixels per row of `nearest` (the attachments' width).
    pub(super) stride: u32,
    pub(super) draw_table: &'a DrawTable,
}

/// One slot's visibility words: the range view's and (where a shadow pass runs) the shadow
/// view's, which a [`CoverageGroup`] fills, and the bindings that resolve each view's. Where
/// they hold one draw, the range view's words are resolved into its attachments, by the
/// shadow mask where there is a shadow view and by the resolve pass where there is none, and
/// the shadow view's are read by the shadow mask as they are. Where they hold several, the
/// resolve passes write both views' attachments, which the shadow mask then reads as the
/// graphics path leaves them.
pub(crate) struct ComputeViews<'a> {
    pub(super) range: ViewWords<'a>,
    pub(super) shadow: Option<ViewWords<'a>>,
    pub(super) resolve: StorageSet,
    pub(super) resolve_shadow: Option<StorageSet>,
}

impl<'a> ComputeViews<'a> {
    /// Visibility words for the views, and the bindings that resolve the range view's into
    /// `range_targets`, and where they hold `several_draws`, the shadow view's into its targets.
    pub fn new(
        ctx: &Arc<GpuContext>,
        pipelines: &ComputeRasterPipelines,
        (range, range_targets): (ComputeTarget<'a>, &ViewTargets),
        shadow: Option<(ComputeTarget<'a>, &ViewTargets)>,
        several_draws: bool,
        name: &str,
    ) -> Result<Self> {
        let words = |kind: ViewKind, view: ComputeTarget<'a>| -> Result<ViewWords<'a>> {
            let (width, height) = view.size;
            let bytes = u64::from(width) * u64::from(height) * VISIBILITY_WORD_BYTES;
            let nearest =
                Buffer::new(ctx, BufferDesc::gpu_storage(bytes), &format!("{name} {kind:?} view visibility words"))?;
            Ok(ViewWords { nearest, stride: width, draw_table: view.draw_table })
        };
        matches_shader_bindings!([RASTER_RESOLVE_COMP] { label, z, dz_dx, dz_dy, DrawTable, Nearest });
        matches_shader_bindings!([RASTER_RESOLVE_SHADOW_COMP] { visibility, DrawTable, Nearest });
        let resolve_set = |pipeline: &ComputePipeline, targets: &ViewTargets, words: &ViewWords, kind: ViewKind| {
            let images: Vec<&Image> = targets.colour.iter().collect();
            let buffers = [&words.draw_table.buffer, &words.nearest];
            StorageSet::new(ctx, pipeline.set_layout, &images, (&[], &buffers), &format!("{name} {kind:?} resolve"))
        };
        let range = words(ViewKind::Range, range)?;
        let resolve = resolve_set(&pipelines.resolve, range_targets, &range, ViewKind::Range)?;
        let (shadow, resolve_shadow) = match shadow {
            Some((view, targets)) => {
                let shadow = words(ViewKind::Shadow, view)?;
                let set = several_draws
                    .then(|| resolve_set(&pipelines.resolve_shadow, targets, &shadow, ViewKind::Shadow))
                    .transpose()?;
                (Some(shadow), set)
            }
            None => (None, None),
        };
        Ok(Self { range, shadow, resolve, resolve_shadow })
    }

    /// What the shadow mask's variant reading words reads (stages/shadow_mask.rs), where these words
    /// include the shadow view's, and the views' pixels per row (range view's, shadow view's).
    pub fn to_mask(&self) -> Option<(WordsToMask<'_>, (u32, u32))> {
        self.shadow.as_ref().map(|shadow| {
            let words = WordsToMask {
                shadow_words: &shadow.nearest,
                range_table: &self.range.draw_table.buffer,
                range_words: &self.range.nearest,
            };
            (words, (self.range.stride, shadow.stride))
        })
    }

    pub(super) fn views(&self) -> impl Iterator<Item = &ViewWords<'a>> {
        std::iter::once(&self.range).chain(&self.shadow)
    }

    pub(super) fn raster_view(view: &ViewWords, area: PixelRect, draw: u32) -> RasterView {
        RasterView { area: [area.col, area.row, area.width, area.height], draw, stride: view.stride, _pad: [0; 2] }
    }

    /// The resolve pass of the range view's words over `area` into `targets`, its colour
    /// attachments, which it leaves in GENERAL layout as a compute pass does. The words hold
    /// `draws` draws, from number `first` in the draw table. Words of one draw are resolved
    /// this way only where no shadow mask follows to resolve them.
    pub fn resolve_step<'s>(
        &'s self,
        pipelines: &'s ComputeRasterPipelines,
        area_in: (&'s ViewTargets, PixelRect),
        (first, draws): (u32, usize),
    ) -> Step<'s> {
        let pipeline = if draws == 1 { &pipelines.resolve } else { &pipelines.resolve_several };
        Self::resolving(&self.range, &self.resolve, pipeline, area_in, first)
    }

    /// The shadow view's resolve pass, as [`ComputeViews::resolve_step`], where its words hold
    /// several draws (the shadow mask reads one draw's as they are); none where these words
    /// have no shadow view or were made for one draw.
    pub fn resolve_shadow_step<'s>(
        &'s self,
        pipelines: &'s ComputeRasterPipelines,
        area_in: (&'s ViewTargets, PixelRect),
        first: u32,
    ) -> Option<Step<'s>> {
        let (words, set) = self.shadow.as_ref().zip(self.resolve_shadow.as_ref())?;
        Some(Self::resolving(words, set, &pipelines.resolve_shadow, area_in, first))
    }

    pub(super) fn resolving<'s>(
        words: &'s ViewWords,
        set: &'s StorageSet,
        pipeline: &'s ComputePipeline,
        (targets, area): (&'s ViewTargets, PixelRect),
        first: u32,
    ) -> Step<'s> {
        let writes: Vec<_> = targets.colour.iter().map(|image| (image, Access::ComputeWrite)).collect();
        let reads = vec![(&words.nearest, Access::ComputeRead), (&words.draw_table.buffer, Access::ComputeRead)];
        let pixels = [area.width, area.height].map(|n| n.div_ceil(8));
        let view = Self::raster_view(words, area, first);
        Step::new(writes, reads, move |_, cmd| set.dispatch(cmd, pipeline, bytemuck::bytes_of(&view), pixels))
    }
}
