//! The pipelines of a rig's pinhole views: the reference view's and the witnesses' raster
//! pipelines (shaders/raster/ with PINHOLE) and the witness mask's, one per shadow test, and
//! the depth test's second pass (stages/walk_list.rs), reading the views' attachments or the
//! compute rasterizer's words.

use super::witness_mask::{WitnessMaskBindings, WitnessMaskConstants};
use crate::error::Result;
use crate::gpu::shaders::layout::spec::WITNESS_MASK_COMP as spec;
use crate::gpu::{shaders, ComputePipeline, GpuContext, SetShape};
use crate::mesh::{LINK_EDGE_MASK, LINK_INDEX_SHIFT, LINK_SAME_WAY};
use crate::render::built_once::built_once;
use crate::render::raster::draw::Projection;
use crate::render::raster::draw::ViewPipelines;
use crate::render::raster::graphics::view_pipelines;
use crate::render::stages::mask_pipelines::MaskPipelines;
use crate::render::stages::walk_list::WalkList;
use crate::render::targets::ViewKind;
use crate::shadow::ShadowTest;
use ash::vk;
use std::sync::{Arc, OnceLock};

pub struct PinholePipelines {
    ctx: Arc<GpuContext>,
    pub reference: ViewPipelines,
    pub witnesses: ViewPipelines,
    /// The mask reading the views' attachments.
    masks: MaskPipelines,
    /// The mask reading the compute rasterizer's words (`FROM_WORDS`), built on first use.
    masks_from_words: OnceLock<MaskPipelines>,
}

/// The witness mask's pipelines (mask_pipelines.rs) of the first pass's code `first` and the
/// depth test's second pass's `walks`, named as the `variant`.
fn witness_mask_pipelines(
    ctx: &Arc<GpuContext>,
    (first, walks): (&[u8], &[u8]),
    variant: &str,
) -> Result<MaskPipelines> {
    MaskPipelines::new(first, Some(walks), |code, test, name| {
        ComputePipeline::new(
            ctx,
            SetShape::storage(WitnessMaskBindings::IMAGES, WitnessMaskBindings::BUFFERS),
            size_of::<WitnessMaskConstants>(),
            code,
            &[
                (spec::TEST, test as u32),
                (spec::TEST_LABEL_SQUARE, ShadowTest::LabelSquare as u32),
                (spec::TEST_DEPTH, ShadowTest::Depth as u32),
                (spec::LINK_INDEX_SHIFT, LINK_INDEX_SHIFT),
                (spec::LINK_SAME_WAY, LINK_SAME_WAY),
                (spec::LINK_EDGE_MASK, LINK_EDGE_MASK),
                (spec::MAX_GROUPS, WalkList::MAX_GROUPS),
            ],
            &format!("witness mask{variant} ({name})"),
        )
    })
}

impl PinholePipelines {
    /// `layout`: the raster pipelines' layout (their push constants), which the renderer owns.
    pub fn new(ctx: &Arc<GpuContext>, layout: vk::PipelineLayout) -> Result<Self> {
        let masks = witness_mask_pipelines(ctx, (shaders::WITNESS_MASK_COMP, shaders::WITNESS_MASK_WALKS_COMP), "")?;
        let reference = view_pipelines(ctx, layout, ViewKind::Range, Projection::Pinhole)?;
        let witnesses = match view_pipelines(ctx, layout, ViewKind::Shadow, Projection::Pinhole) {
            Ok(witnesses) => witnesses,
            Err(e) => {
                reference.destroy(ctx);
                return Err(e);
            }
        };
        Ok(Self { ctx: ctx.clone(), reference, witnesses, masks, masks_from_words: OnceLock::new() })
    }

    /// The mask reading the views' attachments.
    pub fn masks(&self) -> &MaskPipelines {
        &self.masks
    }

    /// The mask reading the compute rasterizer's words, built on first use (by a slot whose
    /// jobs the compute rasterizer may draw).
    pub fn build_masks_from_words(&self) -> Result<&MaskPipelines> {
        built_once(&self.ctx, &self.masks_from_words, || {
            let code = (shaders::WITNESS_MASK_WORDS_COMP, shaders::WITNESS_MASK_WORDS_WALKS_COMP);
            witness_mask_pipelines(&self.ctx, code, " from words")
        })
    }

    /// The mask reading the compute rasterizer's words, where a slot built it.
    pub fn masks_from_words(&self) -> Option<&MaskPipelines> {
        self.masks_from_words.get()
    }
}

impl Drop for PinholePipelines {
    fn drop(&mut self) {
        self.reference.destroy(&self.ctx);
        self.witnesses.destroy(&self.ctx);
    }
}
