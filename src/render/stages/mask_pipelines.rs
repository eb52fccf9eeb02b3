//! A shadow test's pipelines, the scanner's mask's (shadow_mask.rs) and a rig's witness mask's
//! (render/pinhole/) alike: one per [`ShadowTest`], the test a specialization constant, and
//! where the variant has one, the depth test's second pass (walk_list.rs). A software
//! rasterizer such as lavapipe runs both sides of a branch on a uniform value, so each test
//! gets a pipeline of its own rather than a branch on a push constant. Their descriptor-set
//! layouts are defined alike, so one set serves them all.

use crate::error::Result;
use crate::gpu::ComputePipeline;
use crate::shadow::ShadowTest;

pub struct MaskPipelines {
    label: ComputePipeline,
    label_square: ComputePipeline,
    depth: ComputePipeline,
    walks: Option<ComputePipeline>,
}

impl MaskPipelines {
    /// The pipelines of the first pass's code `first`, one a test, and of the second pass's
    /// code `walks` where the variant has one, each built by `pipeline(code, test, name)`.
    pub fn new(
        first: &[u8],
        walks: Option<&[u8]>,
        pipeline: impl Fn(&[u8], ShadowTest, &str) -> Result<ComputePipeline>,
    ) -> Result<Self> {
        Ok(Self {
            label: pipeline(first, ShadowTest::Label, "label test")?,
            label_square: pipeline(first, ShadowTest::LabelSquare, "2x2 label test")?,
            depth: pipeline(first, ShadowTest::Depth, "depth test")?,
            walks: walks.map(|code| pipeline(code, ShadowTest::Depth, "depth test's walks")).transpose()?,
        })
    }

    /// The first pass's pipeline of `test`.
    pub fn for_test(&self, test: ShadowTest) -> &ComputePipeline {
        match test {
            ShadowTest::Label => &self.label,
            ShadowTest::LabelSquare => &self.label_square,
            ShadowTest::Depth => &self.depth,
        }
    }

    /// The second pass `test` takes, where it takes one: the depth test's walks from the
    /// pixels the first listed, in the variants that have them.
    pub fn second_pass(&self, test: ShadowTest) -> Option<&ComputePipeline> {
        self.walks.as_ref().filter(|_| test == ShadowTest::Depth)
    }
}
