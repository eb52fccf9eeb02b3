//! The compute pass that accumulates one hypothesis' verification counts
//! (shaders/verify/score.comp, src/verify/counts.rs).

use super::area::BlockRays;
use super::counts::{N0_WORD, N1_MINUS_WORD, N1_PLUS_WORD, SCALARS};
use crate::error::Result;
use crate::gpu::shaders::layout::spec::SCORE_COMP as spec;
use crate::gpu::shaders::{matches_shader_bindings, matches_shader_struct};
use crate::gpu::{shaders, Buffer, ComputePipeline, GpuContext, Image, SetShape, StorageSet};
use ash::vk;
use std::sync::{Arc, OnceLock};

/// Push constants of the score pass; matches `shaders/verify/score.comp`.
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
pub struct ScoreConstants {
    /// This hypothesis' first word in its slot's counts (src/verify/batch.rs).
    pub counts_offset: u32,
    pub width: u32,
    pub height: u32,
    /// The range view's local origin's z: z = stored offset + z_origin (`ViewGrid::local_origin`).
    pub z_origin: f32,
    pub region: [u32; 4],
    pub surfaces: u32,
    pub segments: u32,
    pub tolerance: f32,
    pub area_scale: f32,
    /// An orthographic view's pitch; a pinhole view's 1/fx, 1/fy (`BlockRays`).
    pub dx: f32,
    pub dy: f32,
    /// A pinhole view's cx, cy.
    pub principal: [f32; 2],
}

matches_shader_struct!(
    ScoreConstants,
    Score {
        counts_offset,
        width,
        height,
        z_origin,
        region,
        surfaces,
        segments,
        tolerance,
        area_scale,
        dx,
        dy,
        principal
    }
);

impl ScoreConstants {
    /// The constants' view fields for `rays` (src/verify/area.rs).
    pub fn with_rays(self, rays: BlockRays) -> Self {
        match rays {
            BlockRays::Orthographic { dx, dy } => Self { dx, dy, principal: [0.0; 2], ..self },
            BlockRays::Pinhole { inverse_focal: [dx, dy], principal } => Self { dx, dy, principal, ..self },
        }
    }
}

/// What a score pass counts from (specialization constants of shaders/verify/score.comp).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct ScoreSources {
    /// The shadow mask's labels, not the range view's.
    pub shadowed: bool,
    /// Drop the pixels an effect lost.
    pub losses: bool,
    /// z from the effects' measured z, not the range view's.
    pub measured_z: bool,
}

impl ScoreSources {
    /// Every combination, in the order of [`ScoreSources::index`].
    const ALL: usize = 8;

    fn index(self) -> usize {
        usize::from(self.shadowed) | usize::from(self.losses) << 1 | usize::from(self.measured_z) << 2
    }

    fn of_index(index: usize) -> Self {
        Self { shadowed: index & 1 != 0, losses: index & 2 != 0, measured_z: index & 4 != 0 }
    }
}

/// Pixels of a row one invocation of the score pass scores (`RUN` in shaders/verify/score.comp): it
/// adds to a counter once for as many of them as count for it in turn. At 1024² on lavapipe,
/// adding a pixel at a time spent about half the pass on its atomics.
const SCORE_RUN: u32 = 16;

/// The score pass's pipelines, one for each [`ScoreSources`] and kind of view (orthographic,
/// pinhole: `BlockRays`), each kind's built on first use and kept for the verifier's life.
/// Their descriptor-set layouts are defined identically, so one set serves them all. A
/// software rasterizer such as lavapipe runs both sides of a branch on a uniform value, so the
/// sources and the kind are chosen by specialization, not by a push constant.
pub(crate) struct ScorePass {
    ctx: Arc<GpuContext>,
    sqrt: (bool, i32),
    /// Orthographic, then pinhole.
    kinds: [OnceLock<Vec<ComputePipeline>>; 2],
}

/// One kind of view's pipelines, by [`ScoreSources::index`].
#[derive(Clone, Copy)]
pub(crate) struct ScorePipelines<'a>(&'a [ComputePipeline]);

impl ScorePass {
    /// The pass, correcting the device's square root to the IEEE one (shaders/verify/score.comp,
    /// `sqrt_rounded`) on a GPU, where Vulkan lets it err by a few ulp; a CPU device's is exact.
    pub fn new(ctx: &Arc<GpuContext>) -> Result<Self> {
        Self::with_sqrt((!ctx.is_cpu(), 0), ctx)
    }

    /// The pass on a device whose square root errs by `ulps`, which it corrects: for the test
    /// standing in for such a device on lavapipe.
    #[cfg(feature = "test-hooks")]
    pub fn with_sqrt_error(ctx: &Arc<GpuContext>, ulps: i32) -> Result<Self> {
        Self::with_sqrt((true, ulps), ctx)
    }

    /// Builds the orthographic views' pipelines, so that a device that cannot build the pass
    /// fails here.
    fn with_sqrt(sqrt: (bool, i32), ctx: &Arc<GpuContext>) -> Result<Self> {
        let pass = Self { ctx: ctx.clone(), sqrt, kinds: Default::default() };
        pass.pipelines(false)?;
        Ok(pass)
    }

    /// The pipelines for an orthographic view, or a pinhole one, built on first use.
    pub fn pipelines(&self, pinhole: bool) -> Result<ScorePipelines<'_>> {
        let cell = &self.kinds[usize::from(pinhole)];
        if let Some(built) = cell.get() {
            return Ok(ScorePipelines(built));
        }
        let (correct, error_ulps) = self.sqrt;
        let ctx = &self.ctx;
        let pipeline = |sources: ScoreSources| {
            let flags = [sources.shadowed, sources.losses, sources.measured_z].map(u32::from);
            // The range view's label and z; the buffers of ScoreInputs.
            ComputePipeline::new(
                ctx,
                SetShape::storage(2, 5),
                size_of::<ScoreConstants>(),
                shaders::SCORE_COMP,
                &[
                    (spec::N1_PLUS, N1_PLUS_WORD),
                    (spec::N1_MINUS, N1_MINUS_WORD),
                    (spec::N0, N0_WORD),
                    (spec::POPULATIONS, SCALARS),
                    (spec::RUN, SCORE_RUN),
                    (spec::USE_SHADOWED, flags[0]),
                    (spec::USE_LOSSES, flags[1]),
                    (spec::USE_MEASURED_Z, flags[2]),
                    (spec::CORRECT_SQRT, u32::from(correct)),
                    (spec::SQRT_ERROR_ULPS, error_ulps as u32),
                    (spec::PINHOLE, u32::from(pinhole)),
                ],
                &format!("verification counts ({sources:?}, pinhole: {pinhole})"),
            )
        };
        let built = (0..ScoreSources::ALL).map(|i| pipeline(ScoreSources::of_index(i))).collect::<Result<_>>()?;
        // A concurrent call may have built them first; either set serves.
        Ok(ScorePipelines(cell.get_or_init(|| built)))
    }

    /// The descriptor set binding what one slot's score passes read and write: the range
    /// view's label and z attachments, the shadowed labels, the sensed image, the slot's
    /// counts, and the effects' losses and measured z (any buffer where there are none: then
    /// they are not read).
    pub fn bindings(&self, ctx: &Arc<GpuContext>, reads: &ScoreInputs) -> Result<ScoreBindings> {
        let buffers = [reads.shadowed_labels, reads.sensed, reads.counts, reads.losses, reads.measured_z];
        matches_shader_bindings!([SCORE_COMP] {
            range_label,
            range_z,
            ShadowedLabels,
            Sensed,
            Counts,
            Losses,
            MeasuredZ,
        });
        let set_layout = self.pipelines(false)?.0[0].set_layout;
        let set = StorageSet::new(ctx, set_layout, &[reads.label, reads.z], (&[], &buffers), "score bindings")?;
        Ok(ScoreBindings { set })
    }
}

/// What a score pass binds (shaders/verify/score.comp, bindings 0 to 6).
pub(crate) struct ScoreInputs<'a> {
    pub label: &'a Image,
    pub z: &'a Image,
    pub shadowed_labels: &'a Buffer,
    /// Per pixel: segment index + 1 (0: no data), and z's bits.
    pub sensed: &'a Buffer,
    pub counts: &'a Buffer,
    pub losses: &'a Buffer,
    pub measured_z: &'a Buffer,
}

pub(crate) struct ScoreBindings {
    set: StorageSet,
}

impl ScoreBindings {
    /// Records the pass counting from `sources` over the constants' region: workgroups of 8×8
    /// invocations, each scoring a run of [`SCORE_RUN`] pixels.
    pub fn record(
        &self,
        cmd: vk::CommandBuffer,
        pipelines: ScorePipelines,
        sources: ScoreSources,
        constants: &ScoreConstants,
    ) {
        let groups = [constants.region[2].div_ceil(8 * SCORE_RUN), constants.region[3].div_ceil(8)];
        self.set.dispatch(cmd, &pipelines.0[sources.index()], bytemuck::bytes_of(constants), groups);
    }
}
