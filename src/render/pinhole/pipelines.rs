//! The pipelines of a rig's pinhole views: the reference view's and the witnesses' raster
//! pipelines (shaders/raster/ with PINHOLE) and the witness mask's, one per shadow test, and
//! the depth test's second pass (stages/walk_list.rs).

use super::witness_mask::{WitnessMaskBindings, WitnessMaskConstants};
use crate::error::Result;
use crate::gpu::shaders::layout::spec::WITNESS_MASK_COMP as spec;
use crate::gpu::{shaders, ComputePipeline, GpuContext, SetShape};
use crate::mesh::{LINK_EDGE_MASK, LINK_INDEX_SHIFT, LINK_SAME_WAY};
use crate::render::raster::draw::Projection;
use crate::render::raster::draw::ViewPipelines;
use crate::render::raster::graphics::view_pipelines;
use crate::render::stages::walk_list::WalkList;
use crate::render::targets::ViewKind;
use crate::shadow::ShadowTest;
use ash::vk;
use std::sync::Arc;

pub struct PinholePipelines {
    ctx: Arc<GpuContext>,
    pub reference: ViewPipelines,
    pub witnesses: ViewPipelines,
    mask_label: ComputePipeline,
    mask_label_square: ComputePipeline,
    mask_depth: ComputePipeline,
    mask_walks: ComputePipeline,
}

impl PinholePipelines {
    /// `layout`: the raster pipelines' layout (their push constants), which the renderer owns.
    pub fn new(ctx: &Arc<GpuContext>, layout: vk::PipelineLayout) -> Result<Self> {
        let mask = |code, test: ShadowTest, name: &str| {
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
                name,
            )
        };
        let first = shaders::WITNESS_MASK_COMP;
        let mask_label = mask(first, ShadowTest::Label, "witness mask (label test)")?;
        let mask_label_square = mask(first, ShadowTest::LabelSquare, "witness mask (2x2 label test)")?;
        let mask_depth = mask(first, ShadowTest::Depth, "witness mask (depth test)")?;
        let walks = shaders::WITNESS_MASK_WALKS_COMP;
        let mask_walks = mask(walks, ShadowTest::Depth, "witness mask (depth test's walks)")?;
        let reference = view_pipelines(ctx, layout, ViewKind::Range, Projection::Pinhole)?;
        let witnesses = match view_pipelines(ctx, layout, ViewKind::Shadow, Projection::Pinhole) {
            Ok(witnesses) => witnesses,
            Err(e) => {
                reference.destroy(ctx);
                return Err(e);
            }
        };
        Ok(Self { ctx: ctx.clone(), reference, witnesses, mask_label, mask_label_square, mask_depth, mask_walks })
    }

    /// The mask pipeline of `test`.
    pub fn mask(&self, test: ShadowTest) -> &ComputePipeline {
        match test {
            ShadowTest::Label => &self.mask_label,
            ShadowTest::LabelSquare => &self.mask_label_square,
            ShadowTest::Depth => &self.mask_depth,
        }
    }

    /// The second pass `test` takes, where it takes one: the depth test's walks from the
    /// pixels the first listed.
    pub fn second_pass(&self, test: ShadowTest) -> Option<&ComputePipeline> {
        (test == ShadowTest::Depth).then_some(&self.mask_walks)
    }
}

impl Drop for PinholePipelines {
    fn drop(&mut self) {
        self.reference.destroy(&self.ctx);
        self.witnesses.destroy(&self.ctx);
    }
}
