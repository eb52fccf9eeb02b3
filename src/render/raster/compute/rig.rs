//! A rig's views on the compute rasterizer (docs/rasterizers.md, "How the compute rasterizer
//! works"): the pinhole reference view and every witness's band, covered two of the same
//! projection a dispatch (each triangle read once for both, as the scanner's range and shadow
//! views are). A job of one draw is covered by the pipelines of one member, as the scanner's
//! jobs are (a software rasterizer reads their constants once for all its invocations), and
//! where the witnesses' shadow test runs (modes `label` and `depth`) takes no resolve: the
//! test reads the words and writes the reference view's attachments itself
//! (pinhole/witness_mask.rs), as the scanner's mask does. A job of several
//! draws makes them the dispatch's members, sharing each view's words as the draws of a
//! scanner view of several objects do (with the ties passes), then resolves its views into the
//! attachments the graphics pipeline draws: the reference view's, and the witnesses'
//! visibility (label, draw, triangle), which the shadow test and every pass after it read
//! unchanged.
//!
//! A pinhole view's coverage is raster.comp's PINHOLE variant (window coordinates divided by
//! w as lavapipe divides, depths larger nearer, cull by winding, clipping as the graphics
//! pipeline's clipper); a directional witness's band is orthographic, covered as a scanner's
//! shadow view is. The words always hold depths (never z keys): the reference view's resolve
//! works its depth and gradient out from the triangle (raster_resolve.comp, PINHOLE), as
//! raster.frag does.

use super::coverage::CoverageRun;
use super::layout::{
    cull_sign, large_queue_bytes, CoverageUniforms, LargeArgs, MemberConstants, RasterView, COVERAGE_MEMBERS,
    DEAL_BLOCK, DEAL_STRIPES, MAX_GROUPS, VISIBILITY_WORD_BYTES,
};
use super::pipelines::{ComputeRasterPipelines, Coverage, CoveragePipelines};
use crate::error::Result;
use crate::gpu::shaders::{self, matches_shader_bindings};
use crate::gpu::{Access, Buffer, BufferDesc, ComputePipeline, GpuContext, SetShape, Step, StorageSet};
use crate::render::built_once::built_once;
use crate::render::raster::draw::{Draw, DrawConstants, Projection};
use crate::render::targets::{ViewKind, ViewTargets};
use crate::sensor::PixelRect;
use crate::shader_contract::{COVERAGE_GROUP, EMPTY_HALF};
use ash::vk;
use std::sync::Arc;

/// The attachments a rig's view is resolved into: the reference view's, or witness attachment
/// k's (src/render/pinhole/, `WitnessAttachment`).
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub(crate) enum RigTarget {
    Reference,
    Witnesses(usize),
}

/// What a slot's rig views are resolved into: the reference view's attachments and each
/// witness attachment's, where the rig has one.
#[derive(Clone, Copy)]
pub(crate) struct RigTargets<'t> {
    pub reference: &'t ViewTargets,
    pub witnesses: [Option<&'t ViewTargets>; 2],
}

impl<'t> RigTargets<'t> {
    fn of(&self, target: RigTarget) -> Option<&'t ViewTargets> {
        match target {
            RigTarget::Reference => Some(self.reference),
            RigTarget::Witnesses(k) => self.witnesses[k],
        }
    }
}

/// One view of a job, as its coverage and resolve see it: the pixels its draws can cover, the
/// pixels it resolves (a witness's band's rows of what the job draws of its attachment: zeros
/// where nothing covers them, as the graphics pipeline clears them), and each draw's constants
/// and cull mode there.
pub(crate) struct RigView<'a> {
    pub area: PixelRect,
    pub resolved: PixelRect,
    pub draws: &'a [(DrawConstants, vk::CullModeFlags)],
}

/// What one view holds in a slot: where it is resolved, its draw table (the resolve reads it;
/// each job writes it), and its resolve's bindings and pipeline.
struct ViewState<'p> {
    target: RigTarget,
    draw_table: Buffer,
    resolve: StorageSet,
    resolve_pipeline: &'p ComputePipeline,
}

/// One coverage dispatch's views (one, or two of the same projection: the second as the
/// shader's shadow view, so that each triangle is read once for both), its buffers and
/// bindings, and its pipelines (small triangles, large): coverage of a job of one draw, and
/// where the slot's jobs may have several draws, coverage of their members and the ties
/// passes.
struct RunState<'p> {
    views: Vec<usize>,
    run: CoverageRun,
    one_draw: CoveragePasses<'p>,
    several: Option<SeveralDraws<'p>>,
}

/// A dispatch's pipelines for jobs of several draws: coverage and the ties passes.
struct SeveralDraws<'p> {
    nearest: CoveragePasses<'p>,
    ties: CoveragePasses<'p>,
}

/// The pipelines of a dispatch's coverage: small triangles, large ones (the queue's start), and
/// where its views are pinhole views, the large triangles the clipper may cut (the queue's
/// end).
#[derive(Clone, Copy)]
struct CoveragePasses<'p> {
    small: &'p ComputePipeline,
    large: &'p ComputePipeline,
    clipped: Option<&'p ComputePipeline>,
}

impl<'p> CoveragePasses<'p> {
    /// The passes of `pipelines` covering one view, or (`both`) two.
    fn of(pipelines: &'p CoveragePipelines, both: bool) -> Self {
        Self { small: pipelines.tiled.covering(both), large: &pipelines.large, clipped: pipelines.clipped.as_ref() }
    }
}

impl<'p> RunState<'p> {
    /// The coverage passes of a job of `draws` draws.
    fn nearest(&self, draws: usize) -> CoveragePasses<'p> {
        if draws == 1 {
            return self.one_draw;
        }
        self.several.as_ref().expect("a slot for jobs of several draws has their pipelines").nearest
    }
}

/// A slot's state for a rig's views on the compute rasterizer: the words of the reference view
/// and of each witness attachment, each view's state in the order of the job's views, and the
/// coverage dispatches that cover them.
pub(crate) struct RigCoverage<'p> {
    words: [Option<(Buffer, u32)>; 3],
    views: Vec<ViewState<'p>>,
    runs: Vec<RunState<'p>>,
}

/// Where a target's words are among [`RigCoverage`]'s.
fn words_index(target: RigTarget) -> usize {
    match target {
        RigTarget::Reference => 0,
        RigTarget::Witnesses(k) => 1 + k,
    }
}

impl ComputeRasterPipelines {
    /// The coverage pipelines of a rig's views of `projection` (`kind`: the nearest, or the
    /// ties passes) whose members are a job's draws, built on first use.
    fn rig_coverage(&self, projection: Projection, kind: Coverage) -> Result<&CoveragePipelines> {
        let cell = match (projection, kind) {
            (Projection::Orthographic, Coverage::Nearest) => &self.grouped,
            (Projection::Orthographic, Coverage::Ties) => &self.ties,
            (Projection::Pinhole, Coverage::Nearest) => &self.pinhole,
            (Projection::Pinhole, Coverage::Ties) => &self.pinhole_ties,
        };
        self.built_for(cell, (kind, projection))
    }

    /// The coverage pipelines of a rig's views of `projection` for a job of one draw: one
    /// member, whose constants a software rasterizer then reads once for all the invocations it
    /// runs together (at an index it cannot prove the same for all, it gathers them invocation
    /// by invocation: raster.comp, MEMBERS), built on first use.
    fn rig_coverage_of_one_draw(&self, projection: Projection) -> Result<&CoveragePipelines> {
        match projection {
            Projection::Orthographic => Ok(&self.single),
            Projection::Pinhole => built_once(&self.ctx, &self.pinhole_one_draw, || {
                CoveragePipelines::new(&self.ctx, 1, Coverage::Nearest, Projection::Pinhole)
            }),
        }
    }

    /// The resolve of a rig's pinhole reference view, built on first use.
    fn resolve_pinhole(&self) -> Result<&ComputePipeline> {
        built_once(&self.ctx, &self.resolve_pinhole, || {
            let shape = SetShape::storage(ViewKind::Range.colour_attachments().len(), 2);
            let several = (shaders::layout::spec::RASTER_RESOLVE_COMP::SEVERAL_DRAWS, 1);
            let code = shaders::RASTER_RESOLVE_PINHOLE_COMP;
            ComputePipeline::new(
                &self.ctx,
                shape,
                size_of::<RasterView>(),
                code,
                &[several],
                "compute raster resolve (pinhole view)",
            )
        })
    }

    /// The resolve pipeline of a view resolved into `target`.
    fn rig_resolve(&self, target: RigTarget) -> Result<&ComputePipeline> {
        match target {
            RigTarget::Reference => self.resolve_pinhole(),
            RigTarget::Witnesses(_) => Ok(&self.resolve_shadow),
        }
    }
}

impl<'p> RigCoverage<'p> {
    /// The words of `target` and their pixels a row, where the slot holds that target: the
    /// witness mask reads them in place of the attachments of a job of one draw.
    pub fn words(&self, target: RigTarget) -> Option<(&Buffer, u32)> {
        self.words[words_index(target)].as_ref().map(|(buffer, stride)| (buffer, *stride))
    }

    /// The reference view's draw table, as each job writes it.
    pub fn reference_draw_table(&self) -> Option<&Buffer> {
        self.views.iter().find(|state| state.target == RigTarget::Reference).map(|state| &state.draw_table)
    }

    /// A slot's state for views resolved into `views`' targets, each of its projection (the
    /// reference view's first, then each witness's, in the order of a job's views), into
    /// `targets`, for jobs of up to `max_draws` draws of up to `max_triangles` each.
    pub fn new(
        ctx: &Arc<GpuContext>,
        pipelines: &'p ComputeRasterPipelines,
        targets: RigTargets,
        views: &[(RigTarget, Projection)],
        (max_triangles, max_draws): (u32, usize),
        name: &str,
    ) -> Result<Self> {
        let words_of = |target: RigTarget| -> Result<Option<(Buffer, u32)>> {
            let Some(attachments) = targets.of(target) else {
                return Ok(None);
            };
            let extent = attachments.depth.desc.extent;
            let (width, height) = (extent.width, extent.height);
            let bytes = u64::from(width) * u64::from(height) * VISIBILITY_WORD_BYTES;
            let buffer =
                Buffer::new(ctx, BufferDesc::gpu_storage(bytes), &format!("{name} {target:?} visibility words"))?;
            Ok(Some((buffer, width)))
        };
        let words =
            [words_of(RigTarget::Reference)?, words_of(RigTarget::Witnesses(0))?, words_of(RigTarget::Witnesses(1))?];
        // Every draw's triangles may be queued in each view of a dispatch (Renderer::computes
        // checks that this much binds for two views).
        let queued = u64::from(max_triangles) * max_draws as u64;
        let several_draws = max_draws > 1;
        let missing =
            |i: usize| crate::error::Error::Scene(format!("{name} rig view {i}: its attachments are missing"));
        let view_words = |i: usize| -> Result<&Buffer> {
            let (target, _) = views[i];
            words[words_index(target)].as_ref().map(|(buffer, _)| buffer).ok_or_else(|| missing(i))
        };
        matches_shader_bindings!([RASTER_RESOLVE_PINHOLE_COMP] { label, z, dz_dx, dz_dy, DrawTable, Nearest });
        matches_shader_bindings!([RASTER_RESOLVE_SHADOW_COMP] { visibility, DrawTable, Nearest });
        let view_states = views
            .iter()
            .enumerate()
            .map(|(i, &(target, _))| {
                let view_name = format!("{name} rig view {i}");
                let attachments = targets.of(target).ok_or_else(|| missing(i))?;
                let table_bytes = (COVERAGE_MEMBERS * size_of::<DrawConstants>()) as u64;
                let draw_table =
                    Buffer::new(ctx, BufferDesc::gpu_storage(table_bytes), &format!("{view_name} draw table"))?;
                let images: Vec<_> = attachments.colour.iter().collect();
                let resolve_pipeline = pipelines.rig_resolve(target)?;
                let buffers = [&draw_table, view_words(i)?];
                let layout = resolve_pipeline.set_layout;
                let resolve = StorageSet::new(ctx, layout, &images, (&[], &buffers), &format!("{view_name} resolve"))?;
                Ok(ViewState { target, draw_table, resolve, resolve_pipeline })
            })
            .collect::<Result<_>>()?;
        // The views of each projection in pairs, in order.
        let mut paired: Vec<Vec<usize>> = Vec::new();
        for projection in [Projection::Pinhole, Projection::Orthographic] {
            let of_it: Vec<usize> = (0..views.len()).filter(|&i| views[i].1 == projection).collect();
            paired.extend(of_it.chunks(2).map(<[usize]>::to_vec));
        }
        let runs = paired
            .into_iter()
            .enumerate()
            .map(|(r, run_views)| {
                let projection = views[run_views[0]].1;
                let both = run_views.len() == 2;
                let one_draw = pipelines.rig_coverage_of_one_draw(projection)?;
                let first = view_words(run_views[0])?;
                let second = if both { view_words(run_views[1])? } else { first };
                let bound: [&Buffer; 2 * COVERAGE_MEMBERS] =
                    std::array::from_fn(|k| if k < COVERAGE_MEMBERS { first } else { second });
                let layout = one_draw.tiled.range.set_layout;
                let large_bytes = large_queue_bytes(queued, run_views.len() as u64);
                let run = CoverageRun::binding(ctx, layout, bound, large_bytes, &format!("{name} rig coverage {r}"))?;
                let several = if several_draws {
                    let nearest = CoveragePasses::of(pipelines.rig_coverage(projection, Coverage::Nearest)?, both);
                    let ties = CoveragePasses::of(pipelines.rig_coverage(projection, Coverage::Ties)?, both);
                    Some(SeveralDraws { nearest, ties })
                } else {
                    None
                };
                Ok(RunState { views: run_views, run, one_draw: CoveragePasses::of(one_draw, both), several })
            })
            .collect::<Result<_>>()?;
        Ok(Self { words, views: view_states, runs })
    }

    /// A job's passes drawing `views` (in the order this state was made for) of `draws` into
    /// `targets`: their words emptied and tables written, each view's coverage, its large
    /// triangles', the ties passes where the job has several draws, and the resolves (timed as
    /// `range`), unless `resolved_by_mask` (a step of nothing in their place, so that in a run
    /// every job's later passes fall in the same stage).
    pub fn steps<'s>(
        &'s self,
        targets: RigTargets<'s>,
        views: &[RigView<'s>],
        draws: &'s [Draw<'s>],
        resolved_by_mask: bool,
    ) -> Vec<Step<'s>> {
        assert!((1..=COVERAGE_MEMBERS).contains(&draws.len()), "1 to {COVERAGE_MEMBERS} draws a rig view");
        assert_eq!(views.len(), self.views.len(), "a job's views are those its slot was made for");
        // Each target's rows that its views resolve, emptied whole.
        let mut emptied = [PixelRect::EMPTY; 3];
        for (state, view) in self.views.iter().zip(views) {
            let rows = &mut emptied[words_index(state.target)];
            *rows = rows.union(view.resolved);
        }
        let fills: Vec<(&'s Buffer, u64, u64)> = self
            .words
            .iter()
            .zip(emptied)
            .filter_map(|(words, rows)| {
                let (buffer, stride) = words.as_ref()?;
                let row_bytes = u64::from(*stride) * VISIBILITY_WORD_BYTES;
                (rows.height > 0).then(|| (buffer, u64::from(rows.row) * row_bytes, u64::from(rows.height) * row_bytes))
            })
            .collect();
        let words: Vec<&'s Buffer> = self.words.iter().flatten().map(|(buffer, _)| buffer).collect();
        let stride_of = |state: &ViewState| self.words[words_index(state.target)].as_ref().map_or(0, |(_, s)| *s);
        // Each dispatch's uniform block (its first view as the range view, its second, where it
        // has one, as the shadow view), and each view's draw table, as this job draws them.
        let mut uniform_blocks: Vec<(&'s RunState, CoverageUniforms)> = Vec::with_capacity(self.runs.len());
        for run in &self.runs {
            let mut uniforms = <CoverageUniforms as bytemuck::Zeroable>::zeroed();
            let covered = |k: usize| {
                let view = run.views.get(k).map(|&i| (&self.views[i], &views[i]));
                view.map(|(state, view)| RasterView {
                    area: rect(view.area),
                    draw: 0,
                    stride: stride_of(state),
                    _pad: [0; 2],
                })
            };
            let (first, second) = (covered(0).expect("a dispatch covers a view"), covered(1));
            let cull_in = |k: usize, m: usize, draw: &Draw| {
                let view = &views[run.views[k.min(run.views.len() - 1)]];
                if view.draws[m].1 == vk::CullModeFlags::NONE {
                    0
                } else {
                    cull_sign(draw.mesh.solidity)
                }
            };
            for (m, draw) in draws.iter().enumerate() {
                let triangles = draw.mesh.index_count / 3;
                uniforms.members[m] = MemberConstants {
                    views: [first, second.unwrap_or(RasterView { area: [0; 4], ..first })],
                    triangles,
                    cull: cull_in(0, m, draw),
                    dealt_rows: triangles.div_ceil(COVERAGE_GROUP) / DEAL_BLOCK / DEAL_STRIPES,
                    place: m as u32,
                    z_keys: 0,
                    second_cull: cull_in(1, m, draw),
                    _pad: [0; 2],
                };
                for (k, &i) in run.views.iter().enumerate() {
                    uniforms.draws[k * COVERAGE_MEMBERS + m] = views[i].draws[m].0;
                }
            }
            uniform_blocks.push((run, uniforms));
        }
        let tables: Vec<(&'s Buffer, Vec<DrawConstants>)> = self
            .views
            .iter()
            .zip(views)
            .map(|(state, view)| (&state.draw_table, view.draws.iter().map(|&(constants, _)| constants).collect()))
            .collect();
        let mut cleared: Vec<(&'s Buffer, Access)> = words.iter().map(|&b| (b, Access::TransferWrite)).collect();
        cleared.extend(self.views.iter().map(|state| (&state.draw_table, Access::TransferWrite)));
        for run in &self.runs {
            cleared.extend([&run.run.large_args, &run.run.uniforms].map(|b| (b, Access::TransferWrite)));
        }
        let prepare = move |ctx: &GpuContext, cmd| {
            let d = &ctx.device;
            // SAFETY: cmd is recording; the step's barrier ordered earlier uses of the buffers;
            // the rows lie within the words, their bytes a multiple of 4; the updates fit the
            // buffers (at most COVERAGE_MEMBERS draws a table).
            unsafe {
                for (buffer, offset, size) in fills {
                    d.cmd_fill_buffer(cmd, buffer.raw, offset, size, EMPTY_HALF);
                }
                for (run, uniforms) in &uniform_blocks {
                    d.cmd_update_buffer(cmd, run.run.large_args.raw, 0, bytemuck::bytes_of(&LargeArgs::EMPTY));
                    d.cmd_update_buffer(cmd, run.run.uniforms.raw, 0, bytemuck::bytes_of(uniforms));
                }
                for (table, entries) in &tables {
                    d.cmd_update_buffer(cmd, table.raw, 0, bytemuck::cast_slice(entries));
                }
            }
        };
        let uses = |queue: Access, args: Access| {
            let mut uses: Vec<(&'s Buffer, Access)> = words.iter().map(|&b| (b, Access::ComputeWrite)).collect();
            for run in &self.runs {
                uses.extend([(&run.run.large, queue), (&run.run.large_args, args)]);
                uses.push((&run.run.uniforms, Access::UniformRead));
            }
            uses
        };
        // How many workgroups the draws need.
        let largest = draws.iter().map(|draw| draw.mesh.index_count / 3).max().unwrap_or(0);
        let groups = largest.div_ceil(COVERAGE_GROUP);
        let coverage_groups = [groups.min(MAX_GROUPS), groups.div_ceil(MAX_GROUPS)];
        let slices = draws.len() as u32;
        let cover = move |_: &GpuContext, cmd| {
            for run in &self.runs {
                run.run.set.dispatch_slices(cmd, run.nearest(draws.len()).small, &[], coverage_groups, slices);
            }
        };
        let large = move |_: &GpuContext, cmd| {
            for run in &self.runs {
                // The triangles the clipper keeps whole, then those it cuts: both only keep the
                // nearer in the words, in any order.
                let passes = run.nearest(draws.len());
                let args = &run.run.large_args;
                run.run.set.dispatch_indirect_at(cmd, passes.large, &[], (args, LargeArgs::START));
                if let Some(clipped) = passes.clipped {
                    run.run.set.dispatch_indirect_at(cmd, clipped, &[], (args, LargeArgs::END));
                }
            }
        };
        let reading_queue = || uses(Access::ComputeRead, Access::IndirectAndComputeRead);
        let mut steps = vec![
            Step::new(Vec::new(), cleared, prepare).timed("coverage: set-up"),
            Step::new(Vec::new(), uses(Access::ComputeWrite, Access::ComputeWrite), cover).timed("coverage"),
            Step::new(Vec::new(), reading_queue(), large).timed("coverage: large triangles"),
        ];
        if draws.len() > 1 {
            // Both ties passes only raise the words' tagged triangles (their depths stay), so
            // they need no barrier between them.
            let record_ties = move |_: &GpuContext, cmd| {
                for run in &self.runs {
                    let several = run.several.as_ref().expect("a slot for jobs of several draws has their pipelines");
                    let (ties, args) = (several.ties, &run.run.large_args);
                    run.run.set.dispatch_slices(cmd, ties.small, &[], coverage_groups, slices);
                    run.run.set.dispatch_indirect_at(cmd, ties.large, &[], (args, LargeArgs::START));
                    if let Some(clipped) = ties.clipped {
                        run.run.set.dispatch_indirect_at(cmd, clipped, &[], (args, LargeArgs::END));
                    }
                }
            };
            steps.push(Step::new(Vec::new(), reading_queue(), record_ties).timed("coverage: ties"));
        }
        if resolved_by_mask {
            steps.push(Step::new(Vec::new(), Vec::new(), |_, _| {}));
            return steps;
        }
        let mut images: Vec<_> = Vec::new();
        for target in [RigTarget::Reference, RigTarget::Witnesses(0), RigTarget::Witnesses(1)] {
            if self.views.iter().any(|state| state.target == target) {
                let attachments = targets.of(target).into_iter().flat_map(|t| &t.colour);
                images.extend(attachments.map(|image| (image, Access::ComputeWrite)));
            }
        }
        let mut reads: Vec<(&'s Buffer, Access)> = words.iter().map(|&b| (b, Access::ComputeRead)).collect();
        reads.extend(self.views.iter().map(|state| (&state.draw_table, Access::ComputeRead)));
        let resolves: Vec<(&'s ViewState, RasterView)> = self
            .views
            .iter()
            .zip(views)
            .map(|(state, view)| {
                (state, RasterView { area: rect(view.resolved), draw: 0, stride: stride_of(state), _pad: [0; 2] })
            })
            .collect();
        let resolve = move |_: &GpuContext, cmd| {
            for (state, view) in &resolves {
                let groups = [view.area[2], view.area[3]].map(|n| n.div_ceil(8));
                if groups[0] > 0 && groups[1] > 0 {
                    state.resolve.dispatch(cmd, state.resolve_pipeline, bytemuck::bytes_of(view), groups);
                }
            }
        };
        steps.push(Step::new(images, reads, resolve).timed("range"));
        steps
    }
}

fn rect(area: PixelRect) -> [u32; 4] {
    [area.col, area.row, area.width, area.height]
}
