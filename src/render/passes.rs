//! The pass list of one job, recorded by one function for `render` and for `verify`:
//!
//! range raster → [shadow raster → shadow mask] → [each named effect] → sink
//!
//! or, in shadow mode `exact`, the range view and its shadowed labels copied from the host
//! (stages/host_view.rs) in place of the three passes before the effects; or, under a rig's
//! pinhole reference view, its views drawn and the witnesses' shadow test (pinhole/) in their
//! place.
//!
//! where the sink is a readback of the images (`render`, a batch of one job) or a caller's
//! compute passes over them (`verify`'s score passes, one job a hypothesis, in
//! verify/batch.rs).
//! The shadow passes are recorded only when the mode and θ ask for them, and an effect's pass
//! only when the effects name it (stages/effects.rs). Each pass is a [`Step`]: the use it makes
//! of each resource, from which the [`Encoder`] derives the barriers, and its commands. A job
//! records its steps one after the other; a run of jobs in different slots records each
//! stage's steps side by side behind one barrier ([`Passes::record_run`]).

use crate::effects::{Effects, EFFECT_ORDER};
use crate::error::{Error, Result};
use crate::gpu::{Access, Buffer, BufferDesc, Encoder, GpuContext, Image, Step, Timestamps};
use crate::render::pinhole::rig_views;
use crate::render::pinhole::{
    MaskWords, PinholeJob, PinholePipelines, WitnessAttachment, WitnessMaskBindings, WitnessSet, WitnessTable,
};
use crate::render::pipelines::Pipelines;
use crate::render::plan::Views;
use crate::render::raster::compute::{
    ComputeRasterPipelines, ComputeTarget, ComputeViews, CoverageGroup, CoverageMember, RigCoverage, RigTarget,
    RigTargets,
};
use crate::render::raster::draw::{record_bands, record_view, Draw, DrawTable, ViewPass};
use crate::render::stages::effects::{EffectBuffers, EffectJob, EffectPipelines, EffectSensor, EffectShape};
use crate::render::stages::host_view::HostView;
use crate::render::stages::shadow_mask::{MaskBindings, MaskConstants};
use crate::render::stages::walk_list::WalkList;
use crate::render::target_pool::{PooledTargets, TargetPool};
use crate::render::targets::{ViewKind, ViewTargets};
use crate::render_output::PassTime;
use crate::sensor::{PixelRect, Scanner, ViewGrid};
use crate::shadow::{ShadowSettings, ShadowTest};
use ash::vk;
use glam::DMat4;
use std::sync::Arc;

/// The render targets and bindings one job renders into; a batch reuses a few in turn.
pub(crate) struct Slot<'a> {
    range: PooledTargets<'a>,
    shadow: Option<PooledTargets<'a>>,
    /// The shadow mask's output labels.
    masked: Option<Buffer>,
    mask_bindings: Option<MaskBindings>,
    /// The pixels the depth test's first pass leaves to its second, where the mask reads the
    /// compute rasterizer's words (stages/shadow_mask.rs).
    walk_list: Option<WalkList>,
    /// The shadow view's draw table, which the mask reads.
    shadow_table: Option<&'a DrawTable>,
    /// The effect passes' outputs, where effects are named.
    effects: Option<EffectBuffers>,
    /// The reflectivity table the effect passes read, where the reflectivity effect is named.
    reflectivities: Option<&'a Buffer>,
    /// The compute rasterizer's state for the range view and the shadow view, where it
    /// renders.
    compute: Option<ComputeViews<'a>>,
    /// A rig's witnesses' images and their shadow test, in shadow modes `label` and `depth` under a
    /// pinhole reference view (src/render/pinhole/).
    witnesses: Option<WitnessSlot<'a>>,
    /// The compute rasterizer's state for a rig's views, where it draws them
    /// (raster/compute/rig.rs).
    rig: Option<RigCoverage<'a>>,
}

/// What a slot holds for a rig's witnesses: the attachments of their images (the
/// pinhole witnesses', the directional witnesses', where the rig has any), the bits of the
/// witnesses that lost each pixel (host-visible for a readback slot), and the shadow test's
/// bindings.
struct WitnessSlot<'a> {
    targets: [Option<PooledTargets<'a>>; 2],
    lost_by: Buffer,
    /// The pixels the depth test's first pass leaves to its second (stages/walk_list.rs).
    walk_list: WalkList,
    /// Each job's witnesses, as its test reads them.
    table: WitnessTable,
    /// Where the slot holds a [`RigCoverage`], its words too (`MaskWords`).
    bindings: WitnessMaskBindings,
    test: ShadowTest,
}

/// What a rig's views are resolved into: the reference view's attachments, and each witness
/// attachment the slot holds.
fn rig_targets<'t>(reference: &'t ViewTargets, witnesses: Option<&'t WitnessSlot>) -> RigTargets<'t> {
    let witnesses = witnesses.map_or([None, None], |w| w.targets.each_ref().map(|t| t.as_deref()));
    RigTargets { reference, witnesses }
}

/// What the witness mask reads of a slot's rig views in place of their attachments, for jobs
/// of one draw (a rig without a kind of witness has the other's words in their place).
fn mask_words<'r>(rig: &'r RigCoverage) -> Option<MaskWords<'r>> {
    let [pinhole, directional] = [0, 1].map(|k| rig.words(RigTarget::Witnesses(k)));
    Some(MaskWords {
        reference_draws: rig.reference_draw_table()?,
        reference: rig.words(RigTarget::Reference)?,
        witnesses: [pinhole.or(directional)?, directional.or(pinhole)?],
    })
}

/// What a slot must hold.
pub(crate) struct SlotShape<'a> {
    /// Range view width and height (the shadow view has the same rows).
    pub size: (u32, u32),
    /// Shadow view width, when a shadow pass runs; its draw table.
    pub shadow: Option<(u32, &'a DrawTable)>,
    /// `render` reads the masked labels on the host; `verify` scores them on the GPU.
    pub sink: SinkKind,
    /// The effect buffers to make, where effects are named.
    pub effects: Option<EffectShape<'a>>,
    /// The range view's draw table, where the compute rasterizer renders (it reads the shadow
    /// view's table from `shadow`).
    pub compute_raster: Option<&'a DrawTable>,
    /// The compute rasterizer's views hold several draws (a scene of several objects): the
    /// slot resolves the shadow view's words too (raster/compute/).
    pub several_draws: bool,
    /// Jobs bring their range view from the host (shadow mode `exact`): the slot holds
    /// shadowed labels without a shadow view.
    pub from_host: bool,
    /// A rig's witnesses, which jobs under a pinhole reference view test in modes `label` and
    /// `depth`.
    pub witnesses: Option<&'a WitnessSet>,
    /// Where the compute rasterizer draws jobs' rig views (raster/compute/rig.rs), the most
    /// triangles a draw of them has and the most draws a job has.
    pub rig_compute: Option<(u32, usize)>,
}

#[derive(Clone, Copy, PartialEq, Eq)]
pub(crate) enum SinkKind {
    Readback,
    Compute,
}

impl<'a> Slot<'a> {
    /// A slot whose targets come from `pool` (and go back to it when the slot is dropped).
    /// `effect_pipelines` are needed where the shape names effects, `raster_pipelines` where
    /// the compute rasterizer renders.
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        ctx: &Arc<GpuContext>,
        p: &Pipelines,
        effect_pipelines: Option<&EffectPipelines>,
        raster_pipelines: Option<&'a ComputeRasterPipelines>,
        pool: &'a TargetPool,
        shape: &SlotShape<'a>,
        name: &str,
    ) -> Result<Self> {
        let (w, h) = shape.size;
        let range = pool.take(ctx, ViewKind::Range, (w, h), &format!("{name} range view"))?;
        // A word a pixel, host-visible where the sink reads it back.
        let per_pixel = || {
            let bytes = u64::from(w) * u64::from(h) * 4;
            match shape.sink {
                SinkKind::Readback => BufferDesc::readback(bytes),
                SinkKind::Compute => BufferDesc::gpu_storage(bytes),
            }
        };
        let shadow = shape
            .shadow
            .map(|(shadow_width, _)| {
                pool.take(ctx, ViewKind::Shadow, (shadow_width, h), &format!("{name} shadow view"))
            })
            .transpose()?;
        // Before the mask's bindings: the mask reads the compute rasterizer's shadow words.
        let compute = match (shape.compute_raster, raster_pipelines) {
            (Some(range_table), Some(rp)) => {
                let range_view = ComputeTarget { size: (w, h), draw_table: range_table };
                let shadow_view = shape.shadow.zip(shadow.as_deref()).map(|((shadow_width, table), targets)| {
                    (ComputeTarget { size: (shadow_width, h), draw_table: table }, targets)
                });
                Some(ComputeViews::new(ctx, rp, (range_view, &range), shadow_view, shape.several_draws, name)?)
            }
            _ => None,
        };
        let (shadow, masked, mask_bindings, walk_list) = match (shape.shadow, shadow) {
            (None, _) if shape.from_host || shape.witnesses.is_some() => {
                (None, Some(Buffer::new(ctx, per_pixel(), &format!("{name} shadowed labels"))?), None, None)
            }
            (Some((_, draw_table)), Some(shadow)) => {
                let masked = Buffer::new(ctx, per_pixel(), &format!("{name} shadowed labels"))?;
                let words = compute.as_ref().and_then(|c| c.to_mask()).map(|(words, _)| words);
                let walk_list =
                    words.as_ref().map(|_| WalkList::new(ctx, u64::from(w) * u64::from(h), name)).transpose()?;
                let to_mask = words.as_ref().zip(walk_list.as_ref());
                let bindings = MaskBindings::new(ctx, &p.mask, &range, &shadow, &masked, &draw_table.buffer, to_mask)?;
                (Some(shadow), Some(masked), Some(bindings), walk_list)
            }
            _ => (None, None, None, None),
        };
        let effects = match (&shape.effects, effect_pipelines) {
            (Some(effect_shape), Some(pipelines)) => {
                Some(EffectBuffers::new(ctx, pipelines, &range.colour, masked.as_ref(), effect_shape, per_pixel, name)?)
            }
            _ => None,
        };
        // The witnesses' attachments, then the words the compute rasterizer draws them in,
        // then the mask that reads either.
        let witness_targets = match (shape.witnesses, &masked) {
            (Some(set), Some(_)) => {
                let targets = WitnessAttachment::ALL.map(|attachment| {
                    let (w, h) = set.sizes[attachment as usize];
                    let kind = format!("{name} {attachment:?} witness views").to_lowercase();
                    (w > 0 && h > 0).then(|| pool.take(ctx, ViewKind::Shadow, (w, h), &kind)).transpose()
                });
                let [pinhole, directional] = targets;
                Some((set, [pinhole?, directional?]))
            }
            _ => None,
        };
        let rig = match (shape.rig_compute, raster_pipelines) {
            (Some(max_triangles), Some(rp)) => {
                let witnesses =
                    witness_targets.as_ref().map_or([None, None], |(_, t)| t.each_ref().map(|t| t.as_deref()));
                let targets = RigTargets { reference: &range, witnesses };
                let views = rig_views(shape.witnesses);
                Some(RigCoverage::new(ctx, rp, targets, &views, max_triangles, name)?)
            }
            _ => None,
        };
        let witnesses = match (witness_targets, &masked) {
            (Some((set, targets)), Some(masked)) => {
                let lost_by = Buffer::new(ctx, per_pixel(), &format!("{name} witness bits"))?;
                let walk_list = WalkList::new(ctx, u64::from(w) * u64::from(h), name)?;
                let table = WitnessTable::new(ctx, name)?;
                let pinhole_pipelines = p.pinhole()?;
                let mask = pinhole_pipelines.masks().for_test(set.test);
                // A rig without a kind of witness binds the other's images and words in their
                // place (a witness set holds one witness at least: the error cannot arise).
                let [pinhole, directional] = [&targets[0], &targets[1]].map(|t| t.as_deref());
                let images = pinhole.or(directional).zip(directional.or(pinhole)).map(|(p, d)| [p, d]);
                let images = images.ok_or_else(|| Error::Scene("a rig's witness set holds no witness".into()))?;
                let words = match &rig {
                    Some(rig) => {
                        pinhole_pipelines.build_masks_from_words()?;
                        mask_words(rig)
                    }
                    None => None,
                };
                let buffers = (masked, &lost_by, &walk_list);
                let bindings = WitnessMaskBindings::new(ctx, mask, (&range, images), buffers, words, &table)?;
                Some(WitnessSlot { targets, lost_by, walk_list, table, bindings, test: set.test })
            }
            _ => None,
        };
        let reflectivities = shape.effects.as_ref().and_then(|e| e.reflectivities);
        let shadow_table = shape.shadow.map(|(_, table)| table);
        Ok(Self {
            range,
            shadow,
            masked,
            mask_bindings,
            walk_list,
            shadow_table,
            effects,
            reflectivities,
            compute,
            witnesses,
            rig,
        })
    }

    /// The bits of the witnesses that lost each pixel, where a rig's shadow test ran
    /// (host-visible for a readback slot).
    pub fn witness_bits(&self) -> Option<&Buffer> {
        self.witnesses.as_ref().map(|w| &w.lost_by)
    }

    /// The range view's label and z attachments, which a compute sink reads.
    pub fn range_label_and_z(&self) -> (&Image, &Image) {
        (self.range.label(), self.range.z())
    }

    /// The compute rasterizer's visibility words, where it renders.
    pub fn compute_views(&self) -> Option<&ComputeViews<'a>> {
        self.compute.as_ref()
    }

    /// The shadowed labels, where a shadow pass ran (host-visible for a readback slot).
    pub fn masked(&self) -> Option<&Buffer> {
        self.masked.as_ref()
    }

    /// The effects' losses and measured z, where effects are named (host-visible for a
    /// readback slot).
    pub fn effect_outputs(&self) -> (Option<&Buffer>, Option<&Buffer>) {
        match &self.effects {
            Some(e) => (Some(&e.losses), e.measured_z.as_ref()),
            None => (None, None),
        }
    }
}

/// One job: posed meshes rendered on planned views over a region of pixels.
pub(crate) struct Job<'a> {
    pub draws: &'a [Draw<'a>],
    /// The first draw's entry in the draw table (the shadow view stores it per pixel).
    pub first_draw_index: u32,
    pub views: &'a Views,
    /// The range pixels to render, mask and score.
    pub area: PixelRect,
    /// The shadow pixels to render (the rows of `area`).
    pub shadow_area: Option<PixelRect>,
    /// Where label 0 of this job's draws is in the reflectivity table.
    pub reflectivity_offset: u32,
    /// The range view cast on the host, in shadow mode `exact`: copied in, not rendered.
    pub host_view: Option<&'a HostView>,
    /// A rig's pinhole views, drawn in place of the range and shadow views.
    pub pinhole: Option<&'a PinholeJob>,
    /// The compute rasterizer renders its views (the slot holds its state).
    pub compute: bool,
}

/// Where a job's images go.
pub(crate) enum Sink<'a> {
    /// Copies of the range view's labels and z (the masked labels stay in the slot).
    Readback { label: &'a Buffer, z: &'a Buffer },
    /// A caller's compute passes over the job's images, recorded after the others, each with
    /// the uses it makes. `reads_range_label`: whether they read the range view's label image
    /// (a score of the unshadowed labels), not only the shadowed labels and z.
    Compute { steps: Box<dyn Fn(JobImages<'a>) -> Vec<Step<'a>> + 'a>, reads_range_label: bool },
}

impl Sink<'_> {
    /// Whether the sink reads the range view's label or gradient images.
    fn reads_range_label(&self) -> bool {
        match self {
            Sink::Readback { .. } => true,
            Sink::Compute { reads_range_label, .. } => *reads_range_label,
        }
    }
}

/// A job's images, as a compute sink finds them.
pub(crate) struct JobImages<'a> {
    pub label: &'a Image,
    pub z: &'a Image,
    /// The shadow mask's output, where a shadow pass ran.
    pub shadowed_labels: Option<&'a Buffer>,
    /// Per pixel, the reason an effect lost it (0 if none did), where effects are named.
    pub losses: Option<&'a Buffer>,
    /// Per pixel, z as measured (range frame), where an effect changes z.
    pub measured_z: Option<&'a Buffer>,
}

/// Timestamps around the passes a job records, and their names: the render summary's
/// "GPU time per pass" lists exactly the passes that ran. A verification's batch times its
/// stages with one too (verify/batch.rs).
pub(crate) struct PassClock<'t> {
    timestamps: &'t Timestamps,
    names: Vec<&'static str>,
}

impl<'t> PassClock<'t> {
    /// Room for every pass of a job (at most a rig's four of coverage on the compute
    /// rasterizer, its resolves and its shadow mask's two; then the effects), and the
    /// timestamp before the first.
    pub const QUERIES: u32 = 8 + EFFECT_ORDER.len() as u32;

    pub fn new(timestamps: &'t Timestamps) -> Self {
        Self { timestamps, names: Vec::new() }
    }

    /// Resets the clock and marks the start of the first pass: record before a job's
    /// coverage (`Passes::record_coverage`) or its passes.
    pub fn start(&mut self, cmd: vk::CommandBuffer) {
        self.timestamps.reset(cmd);
        self.timestamps.write(cmd, 0);
    }

    /// Marks the end of pass `name`; a lap past the timestamps' room is not timed.
    pub fn lap(&mut self, cmd: vk::CommandBuffer, name: &'static str) {
        if self.names.len() as u32 + 1 >= self.timestamps.count() {
            return;
        }
        self.names.push(name);
        self.timestamps.write(cmd, self.names.len() as u32);
    }

    /// The recorded passes with their times, once the submission finished.
    pub fn times(&self) -> Result<Vec<PassTime>> {
        (0..)
            .zip(&self.names)
            .map(|(i, &name)| Ok(PassTime { name, ms: self.timestamps.millis_between(i, i + 1)?, on_cpu: false }))
            .collect()
    }
}

/// Why a shadow pass has a scanner: only the paper's scanner's jobs have shadow views.
const SHADOW_SENSOR: &str = "a shadow view is planned for the paper's scanner alone";

/// What is constant over the jobs of one submission.
pub(crate) struct Passes<'a> {
    pub pipelines: &'a Pipelines,
    /// Present where the compute rasterizer renders views.
    pub raster_pipelines: Option<&'a ComputeRasterPipelines>,
    /// Present where effects are named, with the sensor as they measure against it.
    pub effect_pipelines: Option<(&'a EffectPipelines, EffectSensor)>,
    /// Present where jobs draw a rig's pinhole views.
    pub pinhole_pipelines: Option<&'a PinholePipelines>,
    /// The paper's scanner, which the shadow pass renders; `None` for a rig's image cast on the
    /// CPU (src/exact/rig.rs), which takes effect passes alone, or its pinhole views drawn.
    pub scanner: Option<&'a Scanner>,
    pub shadow: ShadowSettings,
    pub effects: &'a Effects,
}

/// A job's shadow pass, where the mode and θ ask for one and the job's rows reach it: the
/// shadow view's targets, grid and area, the mask's output and bindings, and the test.
type ShadowPass<'s> = (&'s ViewTargets, &'s ViewGrid, PixelRect, &'s Buffer, &'s MaskBindings, ShadowTest);

/// A job the compute rasterizer renders: its slot's words, the pipelines, the first draw's
/// index in the draw tables and the draws.
type ComputeJob<'s, 'p> = (&'s ComputeViews<'s>, &'p ComputeRasterPipelines, (u32, &'s [Draw<'s>]));

impl<'p> Passes<'p> {
    /// The compute rasterizer's state and pipelines for a job it renders (raster/compute/),
    /// with its draws and the first's index in the draw tables.
    fn compute_job<'s>(&self, slot: &'s Slot<'s>, job: &'s Job<'s>) -> Option<ComputeJob<'s, 'p>> {
        match (&slot.compute, self.raster_pipelines, job.host_view) {
            (Some(state), Some(rp), None) if job.compute => Some((state, rp, (job.first_draw_index, job.draws))),
            _ => None,
        }
    }

    fn shadow_pass<'s>(&self, slot: &'s Slot<'s>, job: &'s Job<'s>) -> Option<ShadowPass<'s>> {
        match (&slot.shadow, &job.views.shadow, job.shadow_area, &slot.masked, &slot.mask_bindings) {
            (Some(targets), Some(grid), Some(area), Some(masked), Some(bindings)) => {
                self.shadow.test().map(|test| (&**targets, grid, area, masked, bindings, test))
            }
            _ => None,
        }
    }

    /// Records the compute rasterizer's coverage of a run of jobs in different slots,
    /// `jobs[i]` the job in the run's slot i, before the jobs' own passes ([`Passes::record`],
    /// [`Passes::record_run`]): `group`'s runs of its members, each in one dispatch, the runs
    /// side by side (their buffers made ready behind one barrier, then their coverage
    /// dispatches behind another, then their large triangles' behind a third). Jobs the
    /// graphics pipeline renders are left to their passes. A job of several draws has a
    /// group of its own ([`CoverageGroup::of_draws`]), its draws the members, and a fourth
    /// stage, its ties passes.
    pub fn record_coverage(&self, enc: &mut Encoder, group: &CoverageGroup, jobs: &[(&Slot, &Job)]) -> Result<()> {
        let Some(rp) = self.raster_pipelines else {
            return Ok(());
        };
        let members: Vec<Option<CoverageMember>> = jobs
            .iter()
            .flat_map(|&(slot, job)| match self.compute_job(slot, job) {
                None => vec![None],
                Some((views, _, (first, draws))) => {
                    let shadow_area = self.shadow_pass(slot, job).map(|(_, _, area, ..)| area);
                    let covered_grids =
                        std::iter::once(&job.views.range).chain(shadow_area.and(job.views.shadow.as_ref()));
                    let finest_pitch = covered_grids.flat_map(|grid| grid.pitch).fold(f64::INFINITY, f64::min);
                    let member = |(index, draw)| CoverageMember {
                        views,
                        range_area: job.area,
                        shadow_area,
                        index,
                        draw,
                        finest_pitch,
                    };
                    (first..).zip(draws).map(|indexed| Some(member(indexed))).collect()
                }
            })
            .collect();
        let mut runs = Vec::new();
        for (run, run_members) in members.chunks(group.members()).enumerate() {
            runs.push(group.steps(rp, run, run_members)?);
        }
        enc.record_in_stages(runs);
        Ok(())
    }

    /// Records one job's passes into the encoder's command buffer, after its coverage where
    /// the compute rasterizer renders it ([`Passes::record_coverage`]). A clock given laps each
    /// pass; its caller started it ([`PassClock::start`]) before the coverage.
    pub fn record<'s>(
        &'s self,
        enc: &mut Encoder,
        slot: &'s Slot<'_>,
        job: &'s Job<'_>,
        sink: &Sink<'s>,
        mut clock: Option<&mut PassClock>,
    ) {
        for step in self.steps(slot, job, sink) {
            let lap = step.lap;
            enc.record_together(vec![step]);
            if let (Some(c), Some(name)) = (&mut clock, lap) {
                c.lap(enc.cmd, name);
            }
        }
    }

    /// Records the passes of a run of jobs in different slots, after their coverage: each
    /// job's first passes behind one barrier for all of them, then each job's second, and so
    /// on. A GPU then runs the jobs' masks side by side, then their scores, where one job at
    /// a time would wait for each pass before the next (`verify`'s batches; the timed
    /// `render` records one job with [`Passes::record`]).
    pub fn record_run<'s>(&'s self, enc: &mut Encoder, jobs: &[(&'s Slot<'_>, &'s Job<'_>, &Sink<'s>)]) {
        enc.record_in_stages(jobs.iter().map(|&(slot, job, sink)| self.steps(slot, job, sink)).collect());
    }

    /// One job's passes in order, each with the uses it makes of its slot's resources.
    fn steps<'s>(&'s self, slot: &'s Slot<'_>, job: &'s Job<'_>, sink: &Sink<'s>) -> Vec<Step<'s>> {
        let (p, sensor) = (self.pipelines, self.scanner);
        let views = job.views;
        if let Some(host_view) = job.host_view {
            let shadowed = slot.masked.as_ref().expect("a slot for host views holds shadowed labels");
            let mut steps = vec![host_view.step(&slot.range, shadowed).timed("cast upload")];
            steps.extend(self.effects_and_sink(slot, job, Some(shadowed), sink));
            return steps;
        }
        if let Some(pinhole) = job.pinhole {
            return self.pinhole_steps(slot, job, pinhole, sink);
        }
        // Room for the rasters, the mask's two passes, an effect and the sink's steps: no
        // growing.
        let mut steps = Vec::with_capacity(9);
        let compute = self.compute_job(slot, job);
        let shadow = self.shadow_pass(slot, job);
        match compute {
            // Both views were covered in one pass (raster/compute/). Words of several draws
            // are resolved into both views' attachments, for the shadow mask that reads them.
            Some((state, rp, (first, draws))) if draws.len() > 1 => {
                steps.push(state.resolve_step(rp, (&slot.range, job.area), (first, draws.len())).timed("range"));
                if let Some((targets, _, area, ..)) = shadow {
                    steps.extend(state.resolve_shadow_step(rp, (targets, area), first).map(|s| s.timed("shadow")));
                }
            }
            // Without a shadow mask to resolve the range view's words of one draw, the resolve
            // pass does.
            Some((state, rp, (index, _))) => match shadow {
                None => steps.push(state.resolve_step(rp, (&slot.range, job.area), (index, 1)).timed("range")),
                // The coverage's time, up to here; and in place of the shadow raster, so that in
                // a run the masks and scores of jobs either rasterizer rendered fall in the same
                // stages, the emptying of the depth test's walk list (its mask takes two passes:
                // stages/shadow_mask.rs), or a step of nothing.
                Some((.., test)) => {
                    steps.push(Step::new(Vec::new(), Vec::new(), |_, _| {}).timed("range and shadow"));
                    match slot.walk_list.as_ref().filter(|_| test == ShadowTest::Depth) {
                        Some(list) => {
                            let empty = move |ctx: &GpuContext, cmd| list.record_emptying(ctx, cmd);
                            steps.push(Step::new(Vec::new(), vec![list.emptied()], empty));
                        }
                        None => steps.push(Step::new(Vec::new(), Vec::new(), |_, _| {})),
                    }
                }
            },
            None => {
                let prepare = attachment_writes(std::iter::once(&*slot.range).chain(slot.shadow.as_deref()));
                let range_pass = ViewPass {
                    pipelines: &p.range,
                    layout: p.raster_layout,
                    targets: &slot.range,
                    grid: &views.range,
                    view_from_range: DMat4::IDENTITY,
                    origin: views.origin,
                    area: job.area,
                };
                let record_range =
                    move |ctx: &GpuContext, cmd| record_view(ctx, cmd, &range_pass, job.draws, job.first_draw_index);
                steps.push(Step::new(prepare, Vec::new(), record_range).timed("range"));
                if let Some((targets, grid, area, ..)) = shadow {
                    let shadow_pass = ViewPass {
                        pipelines: &p.shadow,
                        layout: p.raster_layout,
                        targets,
                        grid,
                        view_from_range: sensor.expect(SHADOW_SENSOR).to_shadow_frame(),
                        origin: views.origin,
                        area,
                    };
                    let record_shadow = move |ctx: &GpuContext, cmd| {
                        record_view(ctx, cmd, &shadow_pass, job.draws, job.first_draw_index)
                    };
                    steps.push(Step::new(Vec::new(), Vec::new(), record_shadow).timed("shadow"));
                }
            }
        }
        let mut shadowed_labels = None;
        if let Some((targets, grid, _, masked, bindings, test)) = shadow {
            // Where the compute rasterizer rendered the views, the mask reads their words and
            // writes the range view's attachments (stages/shadow_mask.rs). The words are bound in a
            // slot that has them for either variant, so their reads are stated either way.
            let words = slot.compute.as_ref().and_then(|c| c.to_mask());
            let constants = MaskConstants::new(sensor.expect(SHADOW_SENSOR), views, grid, job.area);
            // The variant reading words where it runs: one choice for the pipeline and for the
            // range view's use. It writes the range view's label and gradient only where a
            // pass after it reads them: an effect, or the sink.
            let reading_words = match (compute, &words) {
                (Some((_, rp, (index, [draw]))), Some((_, strides))) => {
                    let read_later = slot.effects.is_some() || sink.reads_range_label();
                    let mask = if read_later { &rp.mask } else { &rp.mask_for_scoring };
                    // The hull faces only where the depth test reads them: found on first use.
                    let hull = (test == ShadowTest::Depth).then(|| draw.mesh.hull_faces()).flatten();
                    Some((mask, constants.reading_words(index, hull, *strides)))
                }
                _ => None,
            };
            let range_use = if reading_words.is_some() { Access::ComputeWrite } else { Access::ComputeRead };
            let mut images = Vec::with_capacity(slot.range.colour.len() + targets.colour.len());
            images.extend(slot.range.colour.iter().map(|image| (image, range_use)));
            images.extend(targets.colour.iter().map(|image| (image, Access::ComputeRead)));
            let mut buffers = Vec::with_capacity(6);
            buffers.push((masked, Access::ComputeWrite));
            buffers.extend(slot.shadow_table.map(|table| (&table.buffer, Access::ComputeRead)));
            if let Some((w, _)) = &words {
                buffers.extend([w.shadow_words, w.range_table, w.range_words].map(|b| (b, Access::ComputeRead)));
            }
            // The depth test's second pass, where the variant takes one: it reads the words and
            // the list, and drops labels. The first writes the list in every test (a validator
            // takes every test's pipeline to write it: one shader).
            let list = slot.walk_list.as_ref().filter(|_| reading_words.is_some());
            let (mask, constants) = reading_words.unwrap_or((&p.mask, constants));
            let second = mask.second_pass(test).zip(list).map(|(walks, list)| {
                let mut walk_buffers = buffers.clone();
                walk_buffers.extend(list.walked());
                let record_walks = move |_: &GpuContext, cmd| bindings.record_walks(cmd, walks, list, &constants);
                Step::new(Vec::new(), walk_buffers, record_walks).timed("shadow mask: walks")
            });
            buffers.extend(list.into_iter().flat_map(WalkList::appended));
            let record_mask = move |_: &GpuContext, cmd| bindings.record(cmd, mask, test, &constants);
            steps.push(Step::new(images, buffers, record_mask).timed("shadow mask"));
            // Jobs without a second pass take a step of nothing in its place, so that in a run
            // the scores of every job fall in the same stage.
            steps.push(second.unwrap_or_else(|| Step::new(Vec::new(), Vec::new(), |_, _| {})));
            shadowed_labels = Some(masked);
        }
        steps.extend(self.effects_and_sink(slot, job, shadowed_labels, sink));
        steps
    }

    /// A job's passes under a rig's pinhole reference view: the reference view and the
    /// witnesses' images drawn (by the compute rasterizer where the job takes it:
    /// raster/compute/rig.rs), the shadow test, then the effects and the sink.
    fn pinhole_steps<'s>(
        &'s self,
        slot: &'s Slot<'_>,
        job: &'s Job<'_>,
        pinhole: &'s PinholeJob,
        sink: &Sink<'s>,
    ) -> Vec<Step<'s>> {
        let pipelines = self.pinhole_pipelines.expect("built for a pass list of pinhole jobs");
        let witnesses = slot.witnesses.as_ref();
        let witness_targets = || witnesses.into_iter().flat_map(|w| w.targets.iter().flatten().map(|t| &**t));
        // First, the job's witnesses written into the slot's table, and the depth test's walk
        // list emptied, for the test's first pass.
        let mut steps: Vec<Step> = witnesses
            .map(|w| {
                let depth = w.test == ShadowTest::Depth;
                let table = &pinhole.witness_table;
                let write = move |ctx: &GpuContext, cmd| {
                    w.table.record_writing(ctx, cmd, table);
                    if depth {
                        w.walk_list.record_emptying(ctx, cmd);
                    }
                };
                let mut written = vec![w.table.written()];
                written.extend(depth.then(|| w.walk_list.emptied()));
                Step::new(Vec::new(), written, write)
            })
            .into_iter()
            .collect();
        // A job of one draw that the compute rasterizer draws is tested from its views' words
        // (which the slot's witness bindings hold where it holds them), and its shadow test
        // writes the reference view's attachments (witness_mask.rs).
        let from_words = match (&slot.rig, witnesses, job.compute, job.draws, pipelines.masks_from_words()) {
            (Some(rig), Some(_), true, [draw], Some(masks)) => mask_words(rig).map(|words| (words, draw, masks)),
            _ => None,
        };
        match (&slot.rig, job.compute) {
            (Some(rig), true) => steps.extend(rig.steps(
                rig_targets(&slot.range, witnesses),
                &pinhole.compute_views(job.area),
                job.draws,
                from_words.is_some(),
            )),
            _ => steps.push(self.pinhole_draw_step(slot, job, pinhole, pipelines)),
        }
        let shadowed = match (witnesses, &slot.masked) {
            (Some(w), Some(masked)) => {
                let mut buffers =
                    vec![(masked, Access::ComputeWrite), (&w.lost_by, Access::ComputeWrite), w.table.read()];
                let (images, masks, constants) = match from_words {
                    Some((words, draw, masks)) => {
                        // The first pass writes the reference view's attachments; both read
                        // the words and the reference view's draw table.
                        let images = slot.range.colour.iter().map(|image| (image, Access::ComputeWrite)).collect();
                        let [pinhole_words, directional_words] = words.witnesses.map(|(buffer, _)| buffer);
                        buffers.extend(
                            [words.reference_draws, words.reference.0, pinhole_words, directional_words]
                                .map(|buffer| (buffer, Access::ComputeRead)),
                        );
                        let hull = draw.mesh.hull_faces().filter(|_| w.test == ShadowTest::Depth);
                        (images, masks, pinhole.mask.reading_words(&words, hull))
                    }
                    None => {
                        let mut images: Vec<_> =
                            slot.range.colour.iter().map(|image| (image, Access::ComputeRead)).collect();
                        images.extend(
                            witness_targets().flat_map(|t| &t.colour).map(|image| (image, Access::ComputeRead)),
                        );
                        (images, pipelines.masks(), pinhole.mask)
                    }
                };
                // The depth test's second pass reads what the first does (from words, not the
                // reference view's attachments it wrote), and the list; it sets labels' and
                // bits' words.
                let second = masks.second_pass(w.test).map(|walks| {
                    let mut walk_buffers = buffers.clone();
                    walk_buffers.extend(w.walk_list.walked());
                    let walk_images = if from_words.is_some() { Vec::new() } else { images.clone() };
                    let walk = move |_: &GpuContext, cmd| w.bindings.record_walks(cmd, walks, &w.walk_list, &constants);
                    Step::new(walk_images, walk_buffers, walk).timed("shadow mask: walks")
                });
                buffers.extend(w.walk_list.appended());
                let mask = masks.for_test(w.test);
                let test = move |_: &GpuContext, cmd| w.bindings.record(cmd, mask, &constants);
                steps.push(Step::new(images, buffers, test).timed("shadow mask"));
                // Jobs without a second pass take a step of nothing in its place, so that in a
                // run the scores of every job fall in the same stage.
                steps.push(second.unwrap_or_else(|| Step::new(Vec::new(), Vec::new(), |_, _| {})));
                Some(masked)
            }
            _ => None,
        };
        steps.extend(self.effects_and_sink(slot, job, shadowed, sink));
        steps
    }

    /// The graphics pipeline's drawing of a job's rig views: the reference view, the pinhole
    /// witnesses' images in projection, the directional witnesses' as the scanner's shadow view
    /// is drawn.
    fn pinhole_draw_step<'s>(
        &'s self,
        slot: &'s Slot<'_>,
        job: &'s Job<'_>,
        pinhole: &'s PinholeJob,
        pipelines: &'s PinholePipelines,
    ) -> Step<'s> {
        let p = self.pipelines;
        let witnesses = slot.witnesses.as_ref();
        let witness_targets = witnesses.into_iter().flat_map(|w| w.targets.iter().flatten().map(|t| &**t));
        let prepare = attachment_writes(std::iter::once(&*slot.range).chain(witness_targets));
        let draw = move |ctx: &GpuContext, cmd| {
            let half_side = ctx.viewport_half_side();
            let reference = [pinhole.reference_band(job.area, half_side)];
            record_bands(
                ctx,
                cmd,
                (&pipelines.reference, p.raster_layout),
                &slot.range,
                job.area,
                &reference,
                job.draws,
            );
            let targets = witnesses.map(|w| &w.targets).into_iter().flatten();
            for (attachment, targets) in WitnessAttachment::ALL.into_iter().zip(targets) {
                let view_pipelines = match attachment {
                    WitnessAttachment::Pinhole => &pipelines.witnesses,
                    WitnessAttachment::Directional => &p.shadow,
                };
                let drawn = pinhole.witness_area(attachment);
                if let Some(targets) = targets.as_deref().filter(|_| drawn.width > 0 && drawn.height > 0) {
                    let bands = pinhole.witness_bands(attachment);
                    record_bands(ctx, cmd, (view_pipelines, p.raster_layout), targets, drawn, &bands, job.draws);
                }
            }
        };
        Step::new(prepare, Vec::new(), draw).timed("range")
    }

    /// The named effects' passes and the sink, after the range view and (where any) the
    /// shadowed labels were written.
    fn effects_and_sink<'s>(
        &'s self,
        slot: &'s Slot<'_>,
        job: &'s Job<'_>,
        shadowed_labels: Option<&'s Buffer>,
        sink: &Sink<'s>,
    ) -> Vec<Step<'s>> {
        let views = job.views;
        let mut steps = Vec::new();
        if let (Some(buffers), Some((pipelines, sensor))) = (&slot.effects, &self.effect_pipelines) {
            // No losses yet, and z 0.0 where no surface is (as the range view is cleared).
            let cleared: Vec<&Buffer> = std::iter::once(&buffers.losses).chain(&buffers.measured_z).collect();
            let uses = cleared.iter().map(|&b| (b, Access::TransferWrite)).collect();
            let clear = move |ctx: &GpuContext, cmd| {
                for buffer in cleared {
                    // SAFETY: cmd is recording; the step's barrier ordered earlier uses of the
                    // buffer.
                    unsafe { ctx.device.cmd_fill_buffer(cmd, buffer.raw, 0, vk::WHOLE_SIZE, 0) };
                }
            };
            steps.push(Step::new(Vec::new(), uses, clear));
            let effect_job = EffectJob {
                region: job.area,
                size: (views.range.width, views.range.height),
                z_origin: views.origin.z as f32,
                use_shadowed: shadowed_labels.is_some(),
                reflectivity_offset: job.reflectivity_offset,
            };
            let mut z_in_buffer = false;
            for effect in self.effects.passes() {
                let reads: Vec<_> = slot.range.colour.iter().map(|image| (image, Access::ComputeRead)).collect();
                let mut used = vec![(&buffers.losses, Access::ComputeWrite)];
                used.extend(buffers.measured_z.as_ref().map(|z| (z, Access::ComputeWrite)));
                used.extend(shadowed_labels.map(|m| (m, Access::ComputeRead)));
                used.extend(slot.reflectivities.map(|r| (r, Access::ComputeRead)));
                let effects = self.effects;
                let record = move |_: &GpuContext, cmd| {
                    buffers.record(cmd, pipelines, effect, (effects, sensor), &effect_job, z_in_buffer)
                };
                steps.push(Step::new(reads, used, record).timed(effect.pass_name()));
                z_in_buffer |= effect.changes_z();
            }
        }
        let (losses, measured_z) = slot.effect_outputs();
        match sink {
            Sink::Readback { label, z } => {
                let sources = vec![(slot.range.label(), Access::TransferRead), (slot.range.z(), Access::TransferRead)];
                let (w, h) = (views.range.width, views.range.height);
                let copies = [(slot.range.label(), *label), (slot.range.z(), *z)];
                let copy = move |_: &GpuContext, cmd| {
                    for (image, buffer) in copies {
                        image.record_copy_to_buffer(cmd, buffer, (w, h));
                    }
                };
                steps.push(Step::new(
                    sources,
                    vec![(*label, Access::TransferWrite), (*z, Access::TransferWrite)],
                    copy,
                ));
                let mut host = vec![(*label, Access::HostRead), (*z, Access::HostRead)];
                host.extend([shadowed_labels, losses, measured_z].into_iter().flatten().map(|b| (b, Access::HostRead)));
                steps.push(Step::new(Vec::new(), host, |_, _| {}));
            }
            Sink::Compute { steps: sink_steps, .. } => {
                let images =
                    JobImages { label: slot.range.label(), z: slot.range.z(), shadowed_labels, losses, measured_z };
                steps.extend(sink_steps(images));
            }
        }
        steps
    }
}

/// The uses a rendering into these views' attachments makes of them: written as colour and
/// depth attachments.
fn attachment_writes<'s>(views: impl Iterator<Item = &'s ViewTargets>) -> Vec<(&'s Image, Access)> {
    views
        .flat_map(|targets| {
            let colour = targets.colour.iter().map(|image| (image, Access::ColorAttachmentWrite));
            colour.chain([(&targets.depth, Access::DepthAttachmentWrite)])
        })
        .collect()
}
