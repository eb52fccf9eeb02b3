//! The coverage dispatches of a submission's slots, jobs in consecutive slots sharing one
//! ([`CoverageGroup`]), and of one job's several draws.

use super::layout::{
    cull_sign, large_queue_bytes, CoverageUniforms, LargeArgs, MemberConstants, RasterView, COVERAGE_MEMBERS,
    DEAL_BLOCK, DEAL_STRIPES, MAX_GROUPS, VISIBILITY_WORD_BYTES,
};
use super::pipelines::{fits_one_tile, ComputeRasterPipelines, Coverage, CoveragePipelines};
use super::views::ComputeViews;
use crate::error::Result;
use crate::gpu::shaders::matches_shader_bindings;
use crate::gpu::{Access, Buffer, BufferDesc, GpuContext, Step, StorageSet};
use crate::render::raster::draw::Draw;
use crate::sensor::PixelRect;
use crate::shader_contract::{COVERAGE_GROUP, EMPTY_HALF};
use ash::vk;
use std::sync::Arc;

/// One job of a coverage dispatch: its slot's words, the areas of its views to cover (the
/// shadow view's where a shadow pass runs), and its draw (number `index` in the draw tables).
pub(crate) struct CoverageMember<'v, 'a> {
    pub views: &'v ComputeViews<'a>,
    pub range_area: PixelRect,
    pub shadow_area: Option<PixelRect>,
    pub index: u32,
    pub draw: &'v Draw<'v>,
    /// The finest pixel pitch of the views it covers, in model units.
    pub finest_pitch: f64,
}

/// The coverage passes of a submission's slots: jobs in consecutive slots share a dispatch,
/// up to `members` of them (the slots in runs of `members`). Each run has its own bindings of
/// its slots' words, queue of large triangles, draws and members' constants, so that a batch
/// may record every run's coverage side by side (`Passes::record_coverage`); each is reused
/// by the run's slots' next jobs.
///
/// Or the coverage of one job's several draws (a view of several objects), its members,
/// which share its words: the passes that keep the nearest, then the ties passes, which keep
/// the one the graphics path's ties rule keeps ([`CoverageGroup::of_draws`]).
pub(crate) struct CoverageGroup {
    pub(super) members: usize,
    pub(super) runs: Vec<CoverageRun>,
    pub(super) shared_words: bool,
}

/// What one run of slots' coverage dispatches use.
pub(super) struct CoverageRun {
    /// The queue of large (triangle, member, view) entries, room for every triangle of every
    /// member in every view, and its parts' indirect dispatches ([`LargeArgs`]).
    pub(super) large: Buffer,
    pub(super) large_args: Buffer,
    /// The members' draws and constants ([`CoverageUniforms`]), written before each coverage
    /// pass.
    pub(super) uniforms: Buffer,
    pub(super) set: StorageSet,
}

impl CoverageGroup {
    /// The coverage of `slots` (their words, in slot order), up to `members` slots a dispatch
    /// (1 to [`COVERAGE_MEMBERS`]; fewer where a queue of large triangles with room for every
    /// triangle of every member would be more than the device binds), rendering draws of no
    /// more than `max_triangles`.
    pub fn new(
        ctx: &Arc<GpuContext>,
        pipelines: &ComputeRasterPipelines,
        slots: &[&ComputeViews],
        members: usize,
        max_triangles: u32,
    ) -> Result<Self> {
        assert!((1..=COVERAGE_MEMBERS).contains(&members), "1 to {COVERAGE_MEMBERS} jobs a coverage dispatch");
        // A triangle is queued in a view of a member at most once. One member's queue always
        // fits: a view whose queue would not stays on the graphics path (Renderer::computes).
        let views = if slots.iter().any(|s| s.shadow.is_some()) { 2 } else { 1 };
        let member_bytes = large_queue_bytes(u64::from(max_triangles), views).max(1);
        let fitting = usize::try_from(ctx.max_storage_buffer_range() / member_bytes).unwrap_or(usize::MAX);
        let members = members.min(fitting).max(1);
        let layout = pipelines.coverage(members)?.tiled.range.set_layout;
        let runs = slots
            .chunks(members)
            .enumerate()
            .map(|(run, slots)| CoverageRun::new(ctx, layout, slots, member_bytes * members as u64, run))
            .collect::<Result<_>>()?;
        Ok(Self { members, runs, shared_words: false })
    }

    /// The coverage of one job of `draws` draws (2 to [`COVERAGE_MEMBERS`]) into `views`, in
    /// one dispatch, the draws of up to `max_triangles` each; refused where its queue of large
    /// triangles would be more than the device binds (`Renderer::computes` leaves such a view
    /// to the graphics pipeline).
    pub fn of_draws(
        ctx: &Arc<GpuContext>,
        pipelines: &ComputeRasterPipelines,
        views: &ComputeViews,
        draws: usize,
        max_triangles: u32,
    ) -> Result<Self> {
        assert!((2..=COVERAGE_MEMBERS).contains(&draws), "2 to {COVERAGE_MEMBERS} draws share a view's words");
        let group = Self::new(ctx, pipelines, &vec![views; draws], draws, max_triangles)?;
        if group.members < draws {
            return Err(crate::error::Error::Unsupported(format!(
                "the compute rasterizer's queue of large triangles for {draws} draws of up to {max_triangles} \
                 triangles is more than this device binds in one buffer"
            )));
        }
        Ok(Self { shared_words: true, ..group })
    }

    /// Jobs a coverage dispatch covers.
    pub fn members(&self) -> usize {
        self.members
    }

    /// The coverage passes of one run of slots (number `run`), `members[m]` the job of its
    /// slot m, where the compute rasterizer renders it: three steps, the run's words and
    /// buffers made ready, the coverage dispatch and the large triangles' (none where no
    /// member is covered); for one job's draws, `members[m]` its draw m, and two more, the
    /// ties passes'. Both views' words are left for the shadow mask, which resolves the
    /// range view (stages/shadow_mask.rs), or for the resolve pass where there is no shadow view
    /// ([`ComputeViews::resolve_step`]).
    pub fn steps<'s>(
        &'s self,
        pipelines: &'s ComputeRasterPipelines,
        run: usize,
        members: &[Option<CoverageMember<'s, '_>>],
    ) -> Result<Vec<Step<'s>>> {
        let covered: Vec<(usize, &CoverageMember)> =
            members.iter().enumerate().filter_map(|(m, member)| Some((m, member.as_ref()?))).collect();
        // A member's place is its index: one job's draws come in the ties order (the lowest
        // label last, as `render` numbers them), as the ties passes and the resolve read them.
        debug_assert!(
            !self.shared_words || covered.windows(2).all(|pair| pair[0].1.draw.label_base >= pair[1].1.draw.label_base),
            "a view's draws come in the ties order"
        );
        if covered.is_empty() {
            return Ok(Vec::new());
        }
        let coverage = pipelines.coverage(self.members)?;
        let buffers = &self.runs[run];
        // Each view's words, where the job covers it: the rows of its area are emptied, not
        // the whole view: a hypothesis costs its footprint, not the image. Nothing reads a
        // word beyond the area's rows, as nothing reads the attachments beyond the area that
        // the graphics pass clears (draw.rs).
        let mut emptied: Vec<(&'s Buffer, u64, u64)> = Vec::new();
        // One job's draws share its words and areas: the first's are all of them.
        let emptying = if self.shared_words { &covered[..1] } else { &covered[..] };
        for (_, member) in emptying {
            let shadow = member.views.shadow.as_ref().zip(member.shadow_area);
            for (view, area) in std::iter::once((&member.views.range, member.range_area)).chain(shadow) {
                let row_bytes = u64::from(view.stride) * VISIBILITY_WORD_BYTES;
                emptied.push((&view.nearest, u64::from(area.row) * row_bytes, u64::from(area.height) * row_bytes));
            }
        }
        let covered_words: Vec<&'s Buffer> = emptied.iter().map(|&(words, ..)| words).collect();
        // Only the covered members' words are declared: the others bound beside them (a
        // graphics job's slot, slots past a short run's end) are never touched, their members
        // covering no triangles.
        let mut cleared: Vec<_> = emptied.iter().map(|&(words, ..)| (words, Access::TransferWrite)).collect();
        cleared.extend([&buffers.large_args, &buffers.uniforms].map(|b| (b, Access::TransferWrite)));
        // The members' draws and constants, written in one command rather than an update and
        // two copies from the draw tables: on a GPU each command costs time of its own.
        let mut uniforms = <CoverageUniforms as bytemuck::Zeroable>::zeroed();
        for &(m, member) in &covered {
            let range = ComputeViews::raster_view(&member.views.range, member.range_area, member.index);
            let shadow = member.views.shadow.as_ref().zip(member.shadow_area);
            let triangles = member.draw.mesh.index_count / 3;
            // A member without a shadow view, in a dispatch covering others' (no batch has
            // one today: the mode and θ decide for all its jobs), covers no pixels there.
            let no_shadow = RasterView { area: [0; 4], ..range };
            uniforms.members[m] = MemberConstants {
                views: [
                    range,
                    shadow.map_or(no_shadow, |(view, area)| ComputeViews::raster_view(view, area, member.index)),
                ],
                triangles,
                cull: cull_sign(member.draw.mesh.solidity),
                dealt_rows: triangles.div_ceil(COVERAGE_GROUP) / DEAL_BLOCK / DEAL_STRIPES,
                place: if self.shared_words { m as u32 } else { 0 },
                z_keys: u32::from(!self.shared_words),
                second_cull: cull_sign(member.draw.mesh.solidity),
                _pad: [0; 2],
            };
            for (slot, view) in [m, COVERAGE_MEMBERS + m].into_iter().zip(member.views.views()) {
                uniforms.draws[slot] = view.draw_table.entries[member.index as usize];
            }
        }
        let prepare = move |ctx: &GpuContext, cmd| {
            let d = &ctx.device;
            // SAFETY: cmd is recording; the step's barrier ordered earlier uses of the buffers;
            // the rows lie within the views' words, and their bytes are a multiple of 4; the
            // updates fill the dispatch's arguments and the uniform block.
            unsafe {
                for (words, offset, size) in emptied {
                    d.cmd_fill_buffer(cmd, words.raw, offset, size, EMPTY_HALF);
                }
                d.cmd_update_buffer(cmd, buffers.large_args.raw, 0, bytemuck::bytes_of(&LargeArgs::EMPTY));
                d.cmd_update_buffer(cmd, buffers.uniforms.raw, 0, bytemuck::bytes_of(&uniforms));
            }
        };
        let uses = |queue: Access, args: Access| {
            let mut uses: Vec<_> = covered_words.iter().map(|&words| (words, Access::ComputeWrite)).collect();
            uses.extend([(&buffers.large, queue), (&buffers.large_args, args)]);
            uses.push((&buffers.uniforms, Access::UniformRead));
            uses
        };
        let triangles = covered.iter().map(|(_, member)| member.draw.mesh.index_count / 3).max().unwrap_or(0);
        let groups = triangles.div_ceil(COVERAGE_GROUP);
        let coverage_groups = [groups.min(MAX_GROUPS), groups.div_ceil(MAX_GROUPS)];
        let both = covered.iter().any(|(_, member)| member.shadow_area.is_some() && member.views.shadow.is_some());
        // Slices up to the last member covered; the others' triangle counts are 0.
        let slices = covered.last().map_or(0, |&(m, _)| m as u32 + 1);
        let one_tile =
            covered.iter().all(|(_, member)| fits_one_tile(member.draw.mesh.longest_edge, member.finest_pitch));
        // An orthographic view's large triangles are all at the queue's start (the clipper
        // never cuts them).
        let passes = |pipelines: &'s CoveragePipelines| -> Result<_> {
            let small = pipelines.small(one_tile)?;
            let small = small.covering(both);
            let cover =
                move |_: &GpuContext, cmd| buffers.set.dispatch_slices(cmd, small, &[], coverage_groups, slices);
            let large = move |_: &GpuContext, cmd| {
                buffers.set.dispatch_indirect_at(cmd, &pipelines.large, &[], (&buffers.large_args, LargeArgs::START))
            };
            Ok((cover, large))
        };
        let (cover, large) = passes(coverage)?;
        // The ties passes read the queue and its dispatch as the first passes left them.
        let reading_queue = || uses(Access::ComputeRead, Access::IndirectAndComputeRead);
        let mut steps = vec![
            Step::new(Vec::new(), cleared, prepare).timed("coverage: set-up"),
            Step::new(Vec::new(), uses(Access::ComputeWrite, Access::ComputeWrite), cover).timed("coverage"),
            Step::new(Vec::new(), reading_queue(), large).timed("coverage: large triangles"),
        ];
        if self.shared_words {
            // Both ties passes only raise the words' tagged triangles (their depths stay), so
            // they need no barrier between them.
            let (cover_ties, large_ties) = passes(pipelines.built(&pipelines.ties, Coverage::Ties)?)?;
            let ties = move |ctx: &GpuContext, cmd| {
                cover_ties(ctx, cmd);
                large_ties(ctx, cmd);
            };
            steps.push(Step::new(Vec::new(), reading_queue(), ties).timed("coverage: ties"));
        }
        Ok(steps)
    }
}

impl CoverageRun {
    /// The buffers and bindings of run number `run`, of `slots` (one a member), with a queue
    /// of `large_bytes`.
    pub(super) fn new(
        ctx: &Arc<GpuContext>,
        layout: vk::DescriptorSetLayout,
        slots: &[&ComputeViews],
        large_bytes: u64,
        run: usize,
    ) -> Result<Self> {
        // Each member's words in each view; where a member or a view is missing, the run's
        // first range view's, never written.
        let member_words = |m: usize, shadow: bool| {
            let views = slots.get(m).unwrap_or(&slots[0]);
            match (shadow, &views.shadow) {
                (true, Some(words)) => &words.nearest,
                _ => &views.range.nearest,
            }
        };
        let words: [&Buffer; 2 * COVERAGE_MEMBERS] =
            std::array::from_fn(|i| member_words(i % COVERAGE_MEMBERS, i >= COVERAGE_MEMBERS));
        Self::binding(ctx, layout, words, large_bytes, &format!("coverage run {run}"))
    }

    /// The buffers and bindings of a run named `name` binding `words` (each member's range
    /// view's, then each member's shadow view's), with a queue of `large_bytes`.
    pub(super) fn binding(
        ctx: &Arc<GpuContext>,
        layout: vk::DescriptorSetLayout,
        words: [&Buffer; 2 * COVERAGE_MEMBERS],
        large_bytes: u64,
        name: &str,
    ) -> Result<Self> {
        let large = Buffer::new(ctx, BufferDesc::gpu_storage(large_bytes.max(4)), &format!("{name} large triangles"))?;
        let args = BufferDesc {
            usage: BufferDesc::gpu_storage(0).usage | vk::BufferUsageFlags::INDIRECT_BUFFER,
            ..BufferDesc::gpu_storage(size_of::<LargeArgs>() as u64)
        };
        let large_args = Buffer::new(ctx, args, &format!("{name} large-triangle dispatch"))?;
        let uniform = BufferDesc {
            usage: vk::BufferUsageFlags::UNIFORM_BUFFER | vk::BufferUsageFlags::TRANSFER_DST,
            ..BufferDesc::gpu_storage(size_of::<CoverageUniforms>() as u64)
        };
        let uniforms = Buffer::new(ctx, uniform, &format!("{name} draws and members"))?;
        matches_shader_bindings!([RASTER_COMP, RASTER_LARGE_COMP, RASTER_TIES_COMP, RASTER_LARGE_TIES_COMP,
            RASTER_PINHOLE_COMP, RASTER_PINHOLE_LARGE_COMP, RASTER_PINHOLE_LARGE_CLIPPED_COMP,
            RASTER_PINHOLE_TIES_COMP, RASTER_PINHOLE_LARGE_TIES_COMP, RASTER_PINHOLE_LARGE_TIES_CLIPPED_COMP] {
            Coverage,
            range_words0,
            range_words1,
            range_words2,
            range_words3,
            shadow_words0,
            shadow_words1,
            shadow_words2,
            shadow_words3,
            Large,
            LargeArgs,
        });
        let mut buffers: Vec<&Buffer> = words.to_vec();
        buffers.extend([&large, &large_args]);
        let set = StorageSet::new(ctx, layout, &[], (&[&uniforms], &buffers), name)?;
        Ok(Self { large, large_args, uniforms, set })
    }
}
