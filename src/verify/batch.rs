//! Many hypotheses per submission: for each, the range pass, the shadow pass, the shadow mask,
//! the named effects and the verification counts, all recorded into one command buffer with
//! no waits between hypotheses.
//!
//! The passes are render's (src/render/passes.rs); this file adds the score pass as their
//! sink. Render targets live in slots reused round-robin, and the hypotheses are recorded in
//! runs, one a slot (as many slots as the verifier asks for and the memory budget holds:
//! [`default_slots`]): the compute rasterizer covers a run's hypotheses in one
//! dispatch, or a few (src/render/raster/compute/, `CoverageGroup`), and then the run's
//! passes go side by side (`Passes::record_run`), each stage of them behind one barrier: a GPU
//! waits for the work before a barrier once a stage for the run, not once a pass for each
//! hypothesis (tests/verify.rs counts them). So that the run's score passes need no barrier
//! between them, each slot adds to counts of its own (synchronization validation sees a
//! buffer bound, and atomics are writes to it); a slot's next hypothesis waits (by barrier)
//! for its previous one's passes. Slot images are sized for the largest view of the batch,
//! and each hypothesis renders its own grid into them, so a hypothesis renders the same alone
//! or in any batch. Each pass touches only the hypothesis' footprint (its bounding sphere's
//! pixels, with a margin), so a small model in a large image costs little; a hypothesis whose
//! footprint misses the image records nothing. The slots' counts, in device-local buffers
//! zeroed first, are copied to host memory at the end and put in the order the verifier reads.

use super::area::{BlockGeometry, BlockRays};
use super::score_pass::{ScoreBindings, ScoreConstants, ScoreInputs, ScorePass, ScorePipelines, ScoreSources};
use crate::effects::Effects;
use crate::error::Result;
use crate::exact::{render_exact, render_rig, ExactObject};
use crate::gpu::{Access, Buffer, BufferDesc, Encoder, GpuContext, Step, Timestamps};
use crate::mesh::Mesh;
use crate::render::pinhole::{draws_rig, Models, PinholeJob, WitnessSet};
use crate::render::{
    draw_table, plan_views, slot_bytes, Draw, EffectShape, GpuMesh, HostView, Job, JobImages, PassClock, PassTime,
    Raster, Renderer, Sink, SinkKind, Slot, SlotShape, ViewKind, Views, FOOTPRINT_MARGIN,
};
use crate::sensor::{PixelRect, Scanner, Sensor, View};
use crate::shadow::{ShadowMode, ShadowSettings};
use ash::vk;
use glam::DMat4;
use std::sync::Mutex;

/// Render-target slots a batch keeps unless the caller says otherwise: the hypotheses of a
/// run go side by side, a barrier a stage for all of them. On a GPU a barrier drains the
/// device, and a stage of one small model's passes for four hypotheses leaves most of a large
/// one idle, so a run there is 16 long (at 256², about 4 MiB a slot); on a CPU device such as
/// lavapipe, which runs a command buffer's dispatches one after another, barriers cost next to
/// nothing and more slots only take memory, so it keeps 4.
pub fn default_slots(ctx: &GpuContext) -> usize {
    if ctx.is_cpu() {
        4
    } else {
        16
    }
}

/// The sensed image as the score pass reads it (uploaded once per `SensedImage`).
pub struct SensedBuffers<'a> {
    /// Per pixel: dense segment index + 1 (0: no data), and z's bits.
    pub pixels: &'a Buffer,
    pub segment_count: u32,
}

/// What is constant over a batch.
pub struct BatchSettings<'a> {
    pub sensor: &'a Sensor,
    /// The paper's scanner, where the sensor is one: the GPU renders its views. Any other
    /// rig's images are cast on the CPU (src/exact/rig.rs), within each hypothesis' footprint.
    pub scanner: Option<&'a Scanner>,
    pub shadow: ShadowSettings,
    pub effects: &'a Effects,
    pub tolerance: f32,
    /// How blocks of the sensor's image turn depths into area (the sensed image's).
    pub blocks: BlockGeometry,
    pub sensed: SensedBuffers<'a>,
    /// Render-target slots: hypotheses recorded side by side in a run.
    pub slots: usize,
    /// Where the batch adds its GPU time by stage, if it is timed.
    pub stage_times: Option<&'a StageTimes>,
}

/// A verification's GPU time by stage of its batches (`Verifier::with_stage_times`): each
/// stage recorded together (a run's coverage set-up, coverage, large triangles, rasters,
/// masks, effects, scores) is timed from the end of the one before, under the name of its
/// first timed pass, and the milliseconds are summed by name, in the order first met.
#[derive(Default)]
pub(crate) struct StageTimes(Mutex<Vec<(&'static str, f64)>>);

impl StageTimes {
    fn add(&self, times: &[PassTime]) {
        let mut summed = self.0.lock().unwrap_or_else(|p| p.into_inner());
        for time in times {
            let Some(ms) = time.ms else { continue };
            match summed.iter_mut().find(|(name, _)| *name == time.name) {
                Some((_, total)) => *total += ms,
                None => summed.push((time.name, ms)),
            }
        }
    }

    /// The sums so far, which start again from nothing.
    pub fn take(&self) -> Vec<(&'static str, f64)> {
        std::mem::take(&mut *self.0.lock().unwrap_or_else(|p| p.into_inner()))
    }
}

/// One hypothesis: a posed mesh and where its counts go (word offsets into the batch's counts).
pub struct BatchItem<'a> {
    pub mesh: &'a GpuMesh,
    /// Bounding sphere of the mesh in model coordinates.
    pub sphere: (glam::DVec3, f64),
    pub pose: DMat4,
    pub surfaces: u32,
    /// The model, for its surfaces' reflectivities.
    pub model: &'a Mesh,
    /// Counts of the shadowed image (or the only image when there is no shadow pass).
    pub counts_offset: usize,
    /// Also count the unshadowed image here, when asked and a shadow pass runs: within the
    /// item's counts, after the shadowed image's.
    pub unshadowed_offset: Option<usize>,
    /// The words its counts take from `counts_offset` (the unshadowed image's included).
    pub counts_words: usize,
}

impl BatchItem<'_> {
    fn draw(&self) -> Draw<'_> {
        Draw { mesh: self.mesh, pose: self.pose, label_base: 0 }
    }
}

/// Bytes of GPU memory each slot of a verification of these posed bounding spheres takes
/// (render/memory.rs, `slot_bytes`): a range view of the sensor's size and a shadow view as
/// wide as the widest hypothesis needs, and with the compute rasterizer room in its queue for
/// every triangle of the largest model (`max_triangles`) in each view. Fails as a batch would
/// on a hypothesis whose views cannot be planned.
pub(crate) fn slot_memory(
    renderer: &Renderer,
    sensor: &Scanner,
    shadow: &ShadowSettings,
    effects: &Effects,
    posed_spheres: impl Iterator<Item = (String, (glam::DVec3, f64))>,
    max_triangles: u64,
) -> Result<u64> {
    let max_side = renderer.context().max_view_side();
    let mut shadow_width = 0;
    for (subject, sphere) in posed_spheres {
        let views = plan_views(sensor, shadow, effects, &[sphere], &|_| "its model".into(), max_side)
            .map_err(|e| e.concerning(&subject))?;
        shadow_width = shadow_width.max(views.shadow.map_or(0, |g| g.width));
    }
    let rows = u64::from(sensor.height);
    let pixels = (rows * u64::from(sensor.width), rows * u64::from(shadow_width));
    let views = if shadow_width > 0 { 2 } else { 1 };
    Ok(slot_bytes(pixels, effects, renderer.may_compute().then_some(max_triangles), views))
}

/// What one batch counted: `counts_words` u32 words, each item's at its `counts_offset`, and
/// which rasterizer rendered each item (none where it rendered nothing: its footprint missed
/// the image, or shadow mode `exact` cast its rays on the host).
pub(crate) struct BatchCounts {
    pub words: Vec<u32>,
    pub rasters: Vec<Option<Raster>>,
}

/// Records and runs one batch.
pub(crate) fn count_batch(
    renderer: &Renderer,
    score_pass: &ScorePass,
    settings: &BatchSettings,
    items: &[BatchItem],
    counts_words: usize,
) -> Result<BatchCounts> {
    if items.is_empty() {
        return Ok(BatchCounts { words: vec![0; counts_words], rasters: Vec::new() });
    }
    let ctx = renderer.context();
    let (width, height) = (settings.sensor.width(), settings.sensor.height());
    let max_side = ctx.max_view_side();
    let to_shadow = settings.scanner.map(Scanner::to_shadow_frame);
    let posed_sphere = |item: &BatchItem| (item.pose.transform_point3(item.sphere.0), item.sphere.1);
    let views: Vec<Views> = items
        .iter()
        .map(|item| match settings.scanner {
            Some(scanner) => {
                let posed = [posed_sphere(item)];
                plan_views(scanner, &settings.shadow, settings.effects, &posed, &|_| "its model".into(), max_side)
            }
            None => Ok(Views::cast(width, height)),
        })
        .collect::<Result<_>>()?;
    // Each hypothesis' pixels that its model can cover (with a margin), in the range view.
    let footprints: Vec<Option<PixelRect>> = items
        .iter()
        .map(|item| {
            let (centre, radius) = posed_sphere(item);
            settings.sensor.reference.footprint(centre, radius, FOOTPRINT_MARGIN)
        })
        .collect();
    let draws: Vec<[Draw; 1]> = items.iter().map(|item| [item.draw()]).collect();
    // Under a rig the GPU draws (modes `none`, `label` and `depth` under a pinhole reference view), each
    // hypothesis' pinhole views within its footprint (render/pinhole/).
    let pinhole = match (&settings.sensor.reference, settings.scanner) {
        (View::Pinhole(reference), None) if draws_rig(settings.sensor, settings.shadow.mode)? => {
            renderer.check_pinhole(reference)?;
            Some((reference, WitnessSet::new(ctx, settings.sensor, &settings.shadow)?))
        }
        _ => None,
    };
    let half_side = ctx.viewport_half_side();
    let witnesses = pinhole.as_ref().and_then(|(_, witnesses)| witnesses.as_ref());
    let pinhole_jobs: Vec<PinholeJob> = match &pinhole {
        Some((reference, _)) => items
            .iter()
            .zip(&draws)
            .zip(&footprints)
            .map(|((item, draws), footprint)| {
                let spheres = [posed_sphere(item)];
                let models = Models { draws, spheres: &spheres, name: &|_| "its model".to_string() };
                let area = footprint.unwrap_or(PixelRect::EMPTY);
                PinholeJob::new(ctx, reference, witnesses, models, area, half_side)
            })
            .collect::<Result<_>>()?,
        None => Vec::new(),
    };
    // Shadow mode `exact`, and any other rig but the scanner: each hypothesis' range view cast
    // on the CPU (a rig's within the hypothesis' footprint), to be copied in.
    let cast = |(item, views): (&BatchItem, &Views), footprint: &Option<PixelRect>| {
        let object = ExactObject { mesh: item.model, pose: item.pose, label_base: 0, solidity: item.mesh.solidity };
        let image = match settings.scanner {
            Some(_) => render_exact(settings.sensor, &[object])?,
            None => {
                render_rig(settings.sensor, &[object], settings.shadow.mode, footprint.unwrap_or(PixelRect::EMPTY))?
            }
        };
        HostView::new(ctx, &image, views.origin.z, "exact range view")
    };
    let host_views: Vec<HostView> = match (settings.scanner, settings.shadow.mode) {
        (Some(_), mode) if mode != ShadowMode::Exact => Vec::new(),
        (None, _) if pinhole.is_some() => Vec::new(),
        _ => items
            .iter()
            .zip(&views)
            .zip(&footprints)
            .map(|(item, footprint)| cast(item, footprint))
            .collect::<Result<_>>()?,
    };
    // Hypothesis i's labels 1..=M at reflectivity_offsets[i] + label; label 0 first.
    let default_reflectivity = settings.effects.reflectivity.map_or(1.0, |r| r.default);
    let mut reflectivity_offsets = Vec::with_capacity(items.len());
    let mut reflectivity_table = Vec::new();
    for item in items {
        reflectivity_offsets.push(reflectivity_table.len() as u32);
        reflectivity_table.push(0.0);
        reflectivity_table.extend(item.model.surface_reflectivities(default_reflectivity).map(|r| r as f32));
    }
    let reflectivities = settings
        .effects
        .reflectivity
        .map(|_| Buffer::with_data(ctx, vk::BufferUsageFlags::STORAGE_BUFFER, &reflectivity_table, "reflectivities"))
        .transpose()?;
    // The slots' views are the sensor's and the widest shadow view; the compute rasterizer's
    // words cover them.
    let shadow_width = views.iter().filter_map(|v| v.shadow.map(|g| g.width)).max();
    let slot_view_pixels = u64::from(height) * u64::from(width.max(shadow_width.unwrap_or(0)));
    // Each hypothesis' footprint in both views; one that misses the image records nothing.
    let jobs: Vec<Option<Job>> = (0..)
        .zip(items.iter().zip(&views).zip(&draws).zip(&reflectivity_offsets).zip(&footprints))
        .map(|(index, ((((item, views), draws), &reflectivity_offset), footprint))| {
            let (centre, radius) = posed_sphere(item);
            let area = (*footprint)?;
            let shadow_area = views.shadow.zip(to_shadow).map(|(g, to_shadow)| {
                let columns =
                    g.footprint(to_shadow.transform_point3(centre), radius, FOOTPRINT_MARGIN).unwrap_or(g.full());
                // Rows are the range view's (a rotation about y keeps y).
                PixelRect { row: area.row, height: area.height, ..columns }
            });
            let footprint = area.pixels();
            let triangles = u64::from(item.mesh.index_count / 3);
            let compute = match (settings.scanner, pinhole_jobs.get(index as usize)) {
                (Some(scanner), _) if host_views.is_empty() => {
                    let reach = views.reach(scanner, (centre, radius));
                    renderer.computes(1, (triangles, triangles), (footprint, reach), slot_view_pixels)
                }
                // A rig's pinhole views (raster/compute/rig.rs).
                (None, Some(job)) => renderer.computes_rig(job, draws, footprint, witnesses),
                _ => false,
            };
            Some(Job {
                draws: draws.as_slice(),
                first_draw_index: index,
                views,
                area,
                shadow_area,
                reflectivity_offset,
                host_view: host_views.get(index as usize),
                pinhole: pinhole_jobs.get(index as usize),
                compute,
            })
        })
        .collect();
    // Hypothesis i is draw i of the table, seen or not.
    let groups = || views.iter().zip(draws.iter().map(|d| d.as_slice()));
    let table = |kind| settings.scanner.map(|scanner| draw_table(ctx, kind, scanner, groups())).transpose();
    let shadow_table = table(ViewKind::Shadow)?.flatten();
    // Every hypothesis is a view of one draw; the table is needed where any renders by compute.
    let compute = jobs.iter().flatten().any(|job| job.compute);
    let range_table = match compute {
        true => table(ViewKind::Range)?.flatten(),
        false => None,
    };
    // The compute rasterizer covers consecutive slots' hypotheses in one dispatch, as many as
    // the renderer asks for (and its queue of large triangles can bind: CoverageGroup).
    let max_triangles = items
        .iter()
        .zip(&jobs)
        .filter(|(_, job)| job.as_ref().is_some_and(|j| j.compute))
        .map(|(i, _)| i.mesh.index_count / 3)
        .max();
    let shape = SlotShape {
        size: (width, height),
        shadow: shadow_width.zip(shadow_table.as_ref()),
        sink: SinkKind::Compute,
        effects: (!settings.effects.is_empty())
            .then(|| EffectShape { changes_z: settings.effects.changes_z(), reflectivities: reflectivities.as_ref() }),
        compute_raster: range_table.as_ref(),
        several_draws: false,
        from_host: !host_views.is_empty(),
        witnesses,
        rig_compute: max_triangles.filter(|_| pinhole.is_some()).map(|t| (t, 1)),
    };
    let slots: Vec<Slot> = (0..settings.slots.min(items.len()))
        .map(|i| renderer.slot(&shape, &format!("slot {i}")))
        .collect::<Result<_>>()?;
    let coverage_views: Vec<_> = slots.iter().filter_map(|slot| slot.compute_views()).collect();
    let coverage = match max_triangles {
        Some(triangles) if coverage_views.len() == slots.len() => {
            let members = renderer.hypotheses_per_dispatch().min(slots.len());
            Some(renderer.coverage_group(&coverage_views, members, triangles)?)
        }
        _ => None,
    };
    // Each recorded hypothesis' slot, its run's slots in turn, and where its counts lie in
    // that slot's counts: a slot's own buffer, so that the runs' score passes, each adding to
    // its slot's, need no barrier between them (synchronization validation sees a buffer
    // bound, and atomics are writes to it).
    let recorded: Vec<(&BatchItem, &Job)> =
        items.iter().zip(&jobs).filter_map(|(item, job)| Some((item, job.as_ref()?))).collect();
    let mut slot_words = vec![0; slots.len()];
    let placed: Vec<(usize, usize)> = (0..recorded.len())
        .map(|n| {
            let slot = n % slots.len();
            let at = slot_words[slot];
            slot_words[slot] += recorded[n].0.counts_words;
            (slot, at)
        })
        .collect();
    let slot_counts: Vec<Buffer> = (0..)
        .zip(&slot_words)
        .map(|(i, &words)| {
            let bytes = (words as u64 * 4).max(4);
            Buffer::new(ctx, BufferDesc::gpu_storage(bytes), &format!("slot {i} verification counts"))
        })
        .collect::<Result<_>>()?;
    let readback_words: usize = slot_words.iter().sum();
    let readback =
        Buffer::new(ctx, BufferDesc::readback((readback_words as u64 * 4).max(4)), "verification counts readback")?;
    // Bound where a slot has no shadowed labels or effect outputs; never read then.
    let placeholder = Buffer::new(ctx, BufferDesc::gpu_storage(4), "placeholder")?;
    let score_bindings: Vec<_> = slots
        .iter()
        .zip(&slot_counts)
        .map(|(slot, counts)| {
            let (label, z) = slot.range_label_and_z();
            let (losses, measured_z) = slot.effect_outputs();
            let inputs = ScoreInputs {
                label,
                z,
                shadowed_labels: slot.masked().unwrap_or(&placeholder),
                sensed: settings.sensed.pixels,
                counts,
                losses: losses.unwrap_or(&placeholder),
                measured_z: measured_z.unwrap_or(&placeholder),
            };
            score_pass.bindings(ctx, &inputs)
        })
        .collect::<Result<_>>()?;

    let passes = renderer.passes(
        (settings.sensor, settings.scanner),
        settings.shadow,
        settings.effects,
        (compute, pinhole.is_some()),
    )?;
    let score_pipelines = score_pass.pipelines(matches!(settings.blocks.rays, BlockRays::Pinhole { .. }))?;
    // Timed stages: a run's three of coverage, its jobs' passes (PassClock::QUERIES less the
    // start) and two of scores at most.
    let laps = recorded.len().div_ceil(slots.len()) * (PassClock::QUERIES as usize + 4) + 1;
    let timestamps = settings
        .stage_times
        .map(|_| Timestamps::new(ctx, u32::try_from(laps).unwrap_or(u32::MAX), "verification stage timestamps"))
        .transpose()?;
    let mut clock = timestamps.as_ref().map(PassClock::new);
    ctx.submit_and_wait("verification batch", |cmd| {
        let mut lap = clock.as_mut().map(|clock| {
            clock.start(cmd);
            move |cmd, name| clock.lap(cmd, name)
        });
        let mut enc = Encoder::new(ctx, cmd);
        if let Some(lap) = &mut lap {
            enc = enc.with_stage_laps(lap);
        }
        let zeroed: Vec<_> = slot_counts.iter().map(|counts| (counts, Access::TransferWrite)).collect();
        enc.access(&[], &zeroed);
        for counts in &slot_counts {
            // SAFETY: cmd is recording; the buffer is not in use.
            unsafe { ctx.device.cmd_fill_buffer(cmd, counts.raw, 0, vk::WHOLE_SIZE, 0) };
        }
        // The jobs in runs of the slots: each run's coverage, then its jobs' passes side by
        // side (Passes::record_run).
        for (run_jobs, run_places) in recorded.chunks(slots.len()).zip(placed.chunks(slots.len())) {
            let in_slots: Vec<_> =
                run_jobs.iter().zip(run_places).map(|(&(_, job), &(slot, _))| (&slots[slot], job)).collect();
            // The compute rasterizer covers up to a group's members in one dispatch, its runs
            // side by side (CoverageGroup).
            if let Some(group) = &coverage {
                passes.record_coverage(&mut enc, group, &in_slots)?;
            }
            let sinks: Vec<_> = run_jobs
                .iter()
                .zip(run_places)
                .map(|(&(item, job), &(slot, at))| {
                    let scoring = ScoreJob {
                        settings,
                        pipelines: score_pipelines,
                        item,
                        job,
                        slot_counts: (&slot_counts[slot], at),
                    };
                    scoring.sink(&score_bindings[slot])
                })
                .collect();
            let run: Vec<_> = in_slots.iter().zip(&sinks).map(|(&(slot, job), sink)| (slot, job, sink)).collect();
            passes.record_run(&mut enc, &run);
        }
        let copied: Vec<_> = slot_counts.iter().map(|counts| (counts, Access::TransferRead)).collect();
        enc.access(&[], &[copied, vec![(&readback, Access::TransferWrite)]].concat());
        let mut base = 0;
        for (counts, &words) in slot_counts.iter().zip(&slot_words) {
            if words > 0 {
                let region = [vk::BufferCopy::default().dst_offset(base as u64 * 4).size(words as u64 * 4)];
                // SAFETY: the slot's counts hold `words` words, and the readback all slots'.
                unsafe { ctx.device.cmd_copy_buffer(cmd, counts.raw, readback.raw, &region) };
            }
            base += words;
        }
        enc.access(&[], &[(&readback, Access::HostRead)]);
        Ok(())
    })?;
    // Each recorded hypothesis' counts, from its slot's, where the verifier reads them; zeros
    // for a hypothesis that recorded nothing.
    let slot_bases: Vec<usize> =
        slot_words.iter().scan(0, |base, &words| Some(std::mem::replace(base, *base + words))).collect();
    if let (Some(times), Some(clock)) = (settings.stage_times, &clock) {
        times.add(&clock.times()?);
    }
    let read: Vec<u32> = readback.read()?;
    let mut words = vec![0; counts_words];
    for (&(item, _), &(slot, at)) in recorded.iter().zip(&placed) {
        let from = slot_bases[slot] + at;
        words[item.counts_offset..item.counts_offset + item.counts_words]
            .copy_from_slice(&read[from..from + item.counts_words]);
    }
    let rasters = jobs
        .iter()
        .map(|job| match job {
            Some(job) if job.host_view.is_none() => Some(if job.compute { Raster::Compute } else { Raster::Graphics }),
            _ => None,
        })
        .collect();
    Ok(BatchCounts { words, rasters })
}

/// What one hypothesis' score passes need: the batch's settings, the item and its job, and its
/// slot's counts with where in them its own start.
struct ScoreJob<'a> {
    settings: &'a BatchSettings<'a>,
    pipelines: ScorePipelines<'a>,
    item: &'a BatchItem<'a>,
    job: &'a Job<'a>,
    slot_counts: (&'a Buffer, usize),
}

impl<'a> ScoreJob<'a> {
    /// The job's sink: its score pass, and a second of the unshadowed labels where the item
    /// asks for it and a shadow pass ran, a step of its own (the counts are written again,
    /// ordered after the first). Else the verifier copies the counts.
    fn sink(self, bindings: &'a ScoreBindings) -> Sink<'a> {
        let Self { settings, pipelines, item, .. } = self;
        let (counts, at) = self.slot_counts;
        let steps = move |images: JobImages<'a>| -> Vec<Step<'a>> {
            let reads = vec![(images.label, Access::ComputeRead), (images.z, Access::ComputeRead)];
            let effect_outputs = [images.shadowed_labels, images.losses, images.measured_z];
            let mut buffers = Vec::with_capacity(2 + effect_outputs.len());
            buffers.extend([(settings.sensed.pixels, Access::ComputeRead), (counts, Access::ComputeWrite)]);
            buffers.extend(effect_outputs.into_iter().flatten().map(|b| (b, Access::ComputeRead)));
            let sources = ScoreSources {
                shadowed: images.shadowed_labels.is_some(),
                losses: images.losses.is_some(),
                measured_z: images.measured_z.is_some(),
            };
            let first = self.constants(at);
            let record = move |_: &GpuContext, cmd| bindings.record(cmd, pipelines, sources, &first);
            let Some(offset) = item.unshadowed_offset.filter(|_| images.shadowed_labels.is_some()) else {
                return vec![Step::new(reads, buffers, record).timed("score")];
            };
            debug_assert!((item.counts_offset..item.counts_offset + item.counts_words).contains(&offset));
            let again = self.constants(at + offset - item.counts_offset);
            let unshadowed = ScoreSources { shadowed: false, ..sources };
            let record_again = move |_: &GpuContext, cmd| bindings.record(cmd, pipelines, unshadowed, &again);
            vec![
                Step::new(reads.clone(), buffers.clone(), record).timed("score"),
                Step::new(reads, buffers, record_again).timed("score (unshadowed)"),
            ]
        };
        // The unshadowed labels are the range view's.
        Sink::Compute { steps: Box::new(steps), reads_range_label: item.unshadowed_offset.is_some() }
    }

    /// The score pass's constants for counts at `offset` in the slot's.
    fn constants(&self, offset: usize) -> ScoreConstants {
        let (settings, job) = (self.settings, self.job);
        ScoreConstants {
            counts_offset: offset as u32,
            width: settings.sensor.width(),
            height: settings.sensor.height(),
            z_origin: job.views.origin.z as f32,
            region: [job.area.col, job.area.row, job.area.width, job.area.height],
            surfaces: self.item.surfaces,
            segments: self.settings.sensed.segment_count,
            tolerance: self.settings.tolerance,
            area_scale: settings.blocks.scale(),
            dx: 0.0,
            dy: 0.0,
            principal: [0.0; 2],
        }
        .with_rays(settings.blocks.rays)
    }
}
