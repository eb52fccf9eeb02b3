//! The pipelines of a rig's pinhole views: the reference view's and the witnesses' raster
//! pipelines (shaders/raster/ with PINHOLE) and the witness mask's, one per label test.

use super::witness_mask::{WitnessMaskBindings, WitnessMaskConstants};
use crate::error::Result;
use crate::gpu::shaders::layout::spec::WITNESS_MASK_COMP as spec;
use crate::gpu::{shaders, ComputePipeline, GpuContext, SetShape};
use crate::render::raster::draw::ViewPipelines;
use crate::render::raster::graphics::{view_pipelines, Projection};
use crate::render::targets::ViewKind;
use crate::shadow::{Neighbourhood, ShadowTest};
use ash::vk;
use std::sync::Arc;

pub struct PinholePipelines {
    ctx: Arc<GpuContext>,
    pub reference: ViewPipelines,
    pub witnesses: ViewPipelines,
    mask_label: ComputePipeline,
    mask_label_square: ComputePipeline,
}

impl PinholePipelines {
    /// `layout`: the raster pipelines' layout (their push constants), which the renderer owns.
    pub fn new(ctx: &Arc<GpuContext>, layout: vk::PipelineLayout) -> Result<Self> {
        let mask = |test: ShadowTest, name: &str| {
            ComputePipeline::new(
                ctx,
                SetShape::storage(WitnessMaskBindings::IMAGES, WitnessMaskBindings::BUFFERS),
                size_of::<WitnessMaskConstants>(),
                shaders::WITNESS_MASK_COMP,
                &[(spec::TEST, test as u32), (spec::TEST_LABEL_SQUARE, ShadowTest::LabelSquare as u32)],
                name,
            )
        };
        let mask_label = mask(ShadowTest::Label, "witness mask (label test)")?;
        let mask_label_square = mask(ShadowTest::LabelSquare, "witness mask (2x2 label test)")?;
        let reference = view_pipelines(ctx, layout, ViewKind::Range, Projection::Pinhole)?;
        let witnesses = match view_pipelines(ctx, layout, ViewKind::Shadow, Projection::Pinhole) {
            Ok(witnesses) => witnesses,
            Err(e) => {
                reference.destroy(ctx);
                return Err(e);
            }
        };
        Ok(Self { ctx: ctx.clone(), reference, witnesses, mask_label, mask_label_square })
    }

    /// The mask pipeline of the label test that reads `neighbourhood`.
    pub fn mask(&self, neighbourhood: Neighbourhood) -> &ComputePipeline {
        match neighbourhood {
            Neighbourhood::Nearest => &self.mask_label,
            Neighbourhood::Square2 => &self.mask_label_square,
        }
    }
}

impl Drop for PinholePipelines {
    fn drop(&mut self) {
        self.reference.destroy(&self.ctx);
        self.witnesses.destroy(&self.ctx);
    }
}
