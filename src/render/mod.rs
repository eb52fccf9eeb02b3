//! Rendering a scene: the range pass, the shadow pass and the shadow-mask compute pass,
//! recorded into one command buffer (passes.rs), then read back. Verification records the
//! same passes, with its score pass as their sink, for many hypotheses per submission
//! (src/verify/batch.rs).
//!
//! A [`Renderer`] owns the device and the compiled pipelines and is meant to be created once
//! and reused: it is `Send + Sync`, and each call records its own command buffer.

mod alone;
mod built_once;
mod gpu_mesh;
mod memory;
mod mesh_cache;
mod passes;
pub(crate) mod pinhole;
mod pipelines;
mod plan;
mod raster;
mod stages;
mod target_pool;
mod targets;

pub use crate::raster_choice::{Crossover, Raster};
pub use crate::render_output::{PassTime, RenderOutput};

pub use alone::DrawnAlone;
pub use gpu_mesh::GpuMesh;
pub(crate) use memory::{rig_slot_bytes, slot_bytes};
pub(crate) use passes::{Job, JobImages, PassClock, Passes, Sink, SinkKind, Slot, SlotShape};
pub use plan::gpu_arithmetic::MAX_SEEN_REACH_PIXELS;
pub(crate) use plan::{plan_views, Views};
use raster::compute::{large_queue_bytes, ComputeViews, CoverageGroup, VISIBILITY_WORD_BYTES};
pub use raster::compute::{COVERAGE_MEMBERS, COVERAGE_STORAGE_BUFFERS, MAX_REACH_PIXELS};
pub(crate) use raster::draw::draw_table;
pub use raster::draw::Draw;
pub(crate) use stages::effects::EffectShape;
pub(crate) use stages::host_view::HostView;
pub use target_pool::{MAX_CHUNKS_IN_FLIGHT, MAX_SLOTS};
pub(crate) use targets::ViewKind;

use crate::effects::{Effects, Reason};
use crate::error::{Error, Result};
use crate::exact::{render_rig_exact, render_scene_exact, ExactImage};
use crate::gpu::{Buffer, BufferDesc, ContextOptions, Encoder, GpuContext, Timestamps};
use crate::limits::{Ledger, MemoryBudget};
use crate::pose::check_rigid;
use crate::render::stages::effects::EffectSensor;
use crate::scene::Scene;
use crate::sensor::{Scanner, Sensor, ViewGrid};
use crate::shadow::{ShadowMode, ShadowSettings};
use mesh_cache::MeshCache;
use pinhole::{PinholeJob, WitnessSet};
use pipelines::Pipelines;
use std::sync::Arc;
use std::time::Instant;
use target_pool::TargetPool;

/// Pixels added around a footprint: one for rounding, one more in the shadow view for the
/// depth test's neighbourhood of the nearest shadow pixel (shaders/stages/shadow_mask.comp).
pub(crate) const FOOTPRINT_MARGIN: u32 = 2;

pub struct Renderer {
    // Dropped in this order: the pipelines before the context they belong to.
    pipelines: Pipelines,
    ctx: Arc<GpuContext>,
    /// The run's account against its memory budget (limits.rs): what the run's inputs hold,
    /// on top of which every plan is checked.
    ledger: Arc<Ledger>,
    meshes: MeshCache,
    targets: TargetPool,
    raster: Raster,
    /// Jobs the compute rasterizer covers in one dispatch (1 to COVERAGE_MEMBERS).
    hypotheses_per_dispatch: usize,
}

/// Triangles a queue of large triangles has room for, in each view, for `draws` draws of up to
/// `largest` (raster/compute/: room for every triangle of every member).
fn queued_triangles(draws: usize, largest: u64) -> u64 {
    largest.saturating_mul(draws as u64)
}

/// Jobs a coverage dispatch covers unless the caller says otherwise
/// ([`Renderer::with_hypotheses_per_dispatch`]): on lavapipe, a dispatch and a barrier cost
/// next to nothing, and a group's member constants, read at an index it cannot prove the same
/// for all its lanes, are loaded lane by lane, which costs more than a group saves.
fn default_hypotheses_per_dispatch(ctx: &GpuContext) -> usize {
    if ctx.is_cpu() {
        1
    } else {
        COVERAGE_MEMBERS
    }
}

impl Renderer {
    pub fn new(options: &ContextOptions) -> Result<Self> {
        Self::with_context(GpuContext::new(options)?)
    }

    /// A renderer on `ctx` with the default memory budget.
    pub fn with_context(ctx: Arc<GpuContext>) -> Result<Self> {
        let pipelines = Pipelines::new(&ctx)?;
        ctx.save_pipeline_cache();
        Ok(Self {
            pipelines,
            hypotheses_per_dispatch: default_hypotheses_per_dispatch(&ctx),
            ctx,
            ledger: Arc::default(),
            meshes: MeshCache::default(),
            targets: TargetPool::default(),
            raster: Raster::default(),
        })
    }

    /// The same renderer, rendering with `raster` (views of more objects than
    /// [`COVERAGE_MEMBERS`] stay on the graphics path; see raster/compute/).
    pub fn with_raster(self, raster: Raster) -> Self {
        Self { raster, ..self }
    }

    pub fn raster(&self) -> Raster {
        self.raster
    }

    /// The same renderer, covering up to `n` hypotheses of a verification batch in one
    /// dispatch of the compute rasterizer's coverage pass (clamped to 1 to
    /// [`COVERAGE_MEMBERS`]). The default is [`COVERAGE_MEMBERS`] on a GPU, where it saves a
    /// dispatch and a barrier per hypothesis, and 1 on a CPU device, where those cost next to
    /// nothing and reading a member's constants costs more (raster/compute/). The images and
    /// counts are the same either way.
    pub fn with_hypotheses_per_dispatch(self, n: usize) -> Self {
        Self { hypotheses_per_dispatch: n.clamp(1, COVERAGE_MEMBERS), ..self }
    }

    pub fn hypotheses_per_dispatch(&self) -> usize {
        self.hypotheses_per_dispatch
    }

    /// Whether the compute rasterizer renders a view of `draws` draws, `triangles` in all, the
    /// largest of `largest`, over `footprint_pixels` (raster/compute/), into visibility
    /// words for views of at most `view_pixels`, its draws reaching `reach_pixels` from the
    /// views' first pixels ([`Views::reach`]). Words this device cannot bind as one storage
    /// buffer (its maxStorageBufferRange: 128 MiB, 16.7 million pixels, on lavapipe), a queue
    /// of large triangles with room for every triangle of `draws` of the largest in both views
    /// (16.7 million triangles there), or corners beyond [`MAX_REACH_PIXELS`] leave the view
    /// to the graphics pipeline.
    pub(crate) fn computes(
        &self,
        draws: usize,
        triangles: (u64, u64),
        footprint: (u64, f64),
        view_pixels: u64,
    ) -> bool {
        self.computes_past(self.crossover(), draws, triangles, footprint, view_pixels)
    }

    /// [`Renderer::computes`], `auto` taking the compute rasterizer past `crossover`.
    pub(crate) fn computes_past(
        &self,
        crossover: Crossover,
        draws: usize,
        (triangles, largest): (u64, u64),
        (footprint_pixels, reach_pixels): (u64, f64),
        view_pixels: u64,
    ) -> bool {
        let range = self.ctx.max_storage_buffer_range();
        let words_fit = view_pixels.saturating_mul(VISIBILITY_WORD_BYTES) <= range;
        let queue_fits = large_queue_bytes(queued_triangles(draws, largest), 2) <= range;
        words_fit
            && queue_fits
            && reach_pixels <= MAX_REACH_PIXELS
            && self.raster.computes((self.supports_compute_raster(), crossover), draws, triangles, footprint_pixels)
    }

    /// Whether this renderer's device can run the compute rasterizer (raster/compute/).
    pub fn supports_compute_raster(&self) -> bool {
        raster::compute::device_supports(&self.ctx)
    }

    /// Where `auto` takes the compute rasterizer on this renderer's device.
    pub fn crossover(&self) -> Crossover {
        Crossover::for_device(self.ctx.is_cpu())
    }

    /// Where `auto` takes the compute rasterizer for a rig's views on this renderer's device:
    /// views of `objects` objects under `sensor` in shadow mode `mode` (`Crossover::for_rig`,
    /// which tells the depth test of one object from the rest; the depth test runs on the GPU
    /// where the rig has witnesses).
    pub fn rig_crossover(&self, sensor: &Sensor, mode: ShadowMode, objects: usize) -> Crossover {
        let depth_test = mode == ShadowMode::Depth && !sensor.witnesses.is_empty();
        Crossover::for_rig(self.ctx.is_cpu(), depth_test && objects == 1)
    }

    /// Refuses a range view of `width`×`height` whose 4-byte-a-pixel storage buffers (the
    /// shadowed labels, the effects' outputs, the sensed image) this device cannot bind.
    pub(crate) fn check_pixel_buffers(&self, (width, height): (u32, u32)) -> Result<()> {
        let bytes = u64::from(width) * u64::from(height) * 4;
        let range = self.ctx.max_storage_buffer_range();
        match bytes <= range {
            true => Ok(()),
            false => Err(Error::Scene(format!(
                "a {width}×{height} image needs {bytes}-byte per-pixel buffers, more than this device binds \
                 ({range} bytes, its maxStorageBufferRange): use at most {} pixels",
                range / 4
            ))),
        }
    }

    /// Whether the compute rasterizer may render any view: this renderer's choice is `compute`,
    /// or `auto` on a device that supports it. Its memory estimates count the visibility words
    /// there.
    pub fn may_compute(&self) -> bool {
        match self.raster {
            Raster::Graphics => false,
            Raster::Compute => true,
            Raster::Auto => self.supports_compute_raster(),
        }
    }

    /// The same renderer, refusing calls that would need more than `budget`.
    pub fn with_memory_budget(self, budget: MemoryBudget) -> Self {
        self.with_ledger(Arc::new(Ledger::new(budget)))
    }

    /// The same renderer, its calls charged to `ledger`: the account of a run whose inputs
    /// (loaded with the same ledger) count against the same budget.
    pub fn with_ledger(self, ledger: Arc<Ledger>) -> Self {
        Self { ledger, ..self }
    }

    pub fn memory_budget(&self) -> MemoryBudget {
        self.ledger.budget()
    }

    pub fn ledger(&self) -> &Arc<Ledger> {
        &self.ledger
    }

    pub fn context(&self) -> &Arc<GpuContext> {
        &self.ctx
    }

    /// Render targets for jobs of this shape (passes.rs).
    pub(crate) fn slot<'a>(&'a self, shape: &SlotShape<'a>, name: &str) -> Result<Slot<'a>> {
        let effect_pipelines = shape.effects.as_ref().map(|_| self.pipelines.effects()).transpose()?;
        let computes = shape.compute_raster.is_some() || shape.rig_compute.is_some();
        let raster_pipelines = computes.then(|| self.pipelines.compute_raster()).transpose()?;
        Slot::new(&self.ctx, &self.pipelines, effect_pipelines, raster_pipelines, &self.targets, shape, name)
    }

    /// The compute rasterizer's coverage of `slots`, `members` a dispatch, for draws of up to
    /// `max_triangles` (raster/compute/).
    pub(crate) fn coverage_group(
        &self,
        slots: &[&ComputeViews],
        members: usize,
        max_triangles: u32,
    ) -> Result<CoverageGroup> {
        CoverageGroup::new(&self.ctx, self.pipelines.compute_raster()?, slots, members, max_triangles)
    }

    /// The pass list for jobs seen by this sensor (`scanner` where it is the paper's scanner)
    /// with these shadow settings and effects, some of whose views the compute rasterizer
    /// renders where `compute`. `pinhole`: some of whose jobs draw a rig's pinhole views.
    pub(crate) fn passes<'a>(
        &'a self,
        (sensor, scanner): (&Sensor, Option<&'a Scanner>),
        shadow: ShadowSettings,
        effects: &'a Effects,
        (compute, pinhole): (bool, bool),
    ) -> Result<Passes<'a>> {
        let effect_pipelines = match effects.is_empty() {
            true => None,
            false => Some((self.pipelines.effects()?, EffectSensor::new(&self.ctx, sensor)?)),
        };
        let raster_pipelines = compute.then(|| self.pipelines.compute_raster()).transpose()?;
        let pinhole_pipelines = pinhole.then(|| self.pipelines.pinhole()).transpose()?;
        let pipelines = &self.pipelines;
        Ok(Passes { pipelines, raster_pipelines, effect_pipelines, pinhole_pipelines, scanner, shadow, effects })
    }

    /// Renders the scene's range image, labels before and after shadowing, and pass times.
    pub fn render(&self, scene: &Scene) -> Result<RenderOutput> {
        scene.sensor.validate()?;
        scene.effects.validate()?;
        // The effects as the sensor has them (disparity's focal length and baseline filled in).
        let effects = scene.effects.for_sensor(&scene.sensor)?;
        let scene = &Scene { effects, ..scene.clone() };
        scene.shadow.validate()?;
        let Some(scanner) = scene.sensor.scanner() else {
            return self.render_rig(scene);
        };
        let label_bases = scene.label_bases()?;
        for (i, object) in scene.objects.iter().enumerate() {
            check_rigid(&object.pose, &format!("object {} ({})", i + 1, object.model_ref))?;
        }
        // Each model once, however many objects share it, and kept for the next render.
        let uploaded: Vec<Arc<GpuMesh>> =
            scene.objects.iter().map(|object| self.meshes.get(&self.ctx, &object.mesh)).collect::<Result<_>>()?;
        let mut draws: Vec<Draw> = uploaded
            .iter()
            .zip(&scene.objects)
            .zip(&label_bases)
            .map(|((mesh, object), &label_base)| Draw { mesh, pose: object.pose, label_base })
            .collect();
        // In the order the graphics path's ties pass draws them (draw.rs: the lowest label
        // last), so that the compute rasterizer's members, which share a view's words and are
        // tagged there with their place in that order, are numbered as their draws
        // (raster/compute/).
        draws.sort_by_key(|draw| std::cmp::Reverse(draw.label_base));
        let spheres: Vec<_> = scene
            .objects
            .iter()
            .map(|o| {
                let (centre, radius) = o.mesh.bounding_sphere();
                (o.pose.transform_point3(centre), radius)
            })
            .collect();
        let name = |i: usize| format!("object {} ({})", i + 1, scene.objects[i].model_ref);
        let views = plan_views(&scanner, &scene.shadow, &scene.effects, &spheres, &name, self.ctx.max_view_side())?;
        let triangles: u64 = scene.objects.iter().map(|o| o.mesh.triangles.len() as u64).sum();
        let largest = scene.objects.iter().map(|o| o.mesh.triangles.len() as u64).max().unwrap_or(0);
        let exact_triangles = (scene.shadow.mode == ShadowMode::Exact).then_some(triangles);
        // The compute rasterizer's choice reads the pixels the objects can cover.
        let footprint: u64 = spheres
            .iter()
            .filter_map(|&(centre, radius)| views.range.footprint(centre, radius, FOOTPRINT_MARGIN))
            .map(|area| area.pixels())
            .sum();
        // Buffers of a word a range pixel hold the shadowed labels and the effects' outputs.
        if views.shadow.is_some() || exact_triangles.is_some() || !scene.effects.is_empty() {
            self.check_pixel_buffers((views.range.width, views.range.height))?;
        }
        let pixels = |g: &ViewGrid| u64::from(g.width) * u64::from(g.height);
        let view_pixels = pixels(&views.range).max(views.shadow.as_ref().map_or(0, pixels));
        let reach = spheres.iter().map(|&sphere| views.reach(&scanner, sphere)).fold(0.0, f64::max);
        let compute = exact_triangles.is_none()
            && self.computes(draws.len(), (triangles, largest), (footprint, reach), view_pixels);
        let queued = queued_triangles(draws.len(), largest);
        self.ledger.check(
            format_args!("rendering a {}×{} image", views.range.width, views.range.height),
            memory::render_bytes(&views, &scene.effects, compute.then_some(queued), exact_triangles),
        )?;
        self.render_views(scene, Some(&scanner), &views, &draws, Source::Passes { compute })
    }

    /// Renders the planned views as `source` says, then their effect passes, and reads them
    /// back.
    fn render_views(
        &self,
        scene: &Scene,
        scanner: Option<&Scanner>,
        views: &Views,
        draws: &[Draw],
        source: Source,
    ) -> Result<RenderOutput> {
        let ctx = &self.ctx;
        let (w, h) = (views.range.width, views.range.height);
        let pixels = u64::from(w) * u64::from(h);
        // Shadow mode `exact`: rays cast on the CPU, timed on the wall clock.
        let source = match source {
            Source::Passes { .. } if scene.shadow.mode == ShadowMode::Exact => {
                Source::Cast(Cast::timed("exact rays", || render_scene_exact(scene))?)
            }
            other => other,
        };
        let compute = matches!(source, Source::Passes { compute: true } | Source::Pinhole { compute: true, .. });
        let (cast, pinhole) = match source {
            Source::Passes { .. } => (None, None),
            Source::Cast(cast) => (Some(cast), None),
            Source::Pinhole { job, witnesses, .. } => (None, Some((job, witnesses))),
        };
        let host_view =
            cast.as_ref().map(|cast| HostView::new(ctx, &cast.image, views.origin.z, "cast range view")).transpose()?;
        let (cast_witness, cast_time) = cast.map(|cast| (cast.image.witness, cast.time)).unzip();
        let job = Job {
            draws,
            first_draw_index: 0,
            views,
            area: views.range.full(),
            shadow_area: views.shadow.map(|g| g.full()),
            reflectivity_offset: 0,
            host_view: host_view.as_ref(),
            pinhole: pinhole.map(|(job, _)| job),
            compute,
        };
        let table = |kind, scanner| draw_table(ctx, kind, scanner, [(views, draws)]);
        let shadow_table = scanner.map(|s| table(ViewKind::Shadow, s)).transpose()?.flatten();
        let range_table = scanner.filter(|_| compute).map(|s| table(ViewKind::Range, s)).transpose()?.flatten();
        let effects = &scene.effects;
        let reflectivities = effects
            .reflectivity
            .map(|r| {
                let table = scene.reflectivity_table(r.default);
                Buffer::with_data(ctx, ash::vk::BufferUsageFlags::STORAGE_BUFFER, &table, "reflectivities")
            })
            .transpose()?;
        let largest = draws.iter().map(|draw| draw.mesh.index_count / 3).max().unwrap_or(0);
        let shape = SlotShape {
            size: (w, h),
            shadow: views.shadow.as_ref().zip(shadow_table.as_ref()).map(|(g, t)| (g.width, t)),
            sink: SinkKind::Readback,
            effects: (!effects.is_empty())
                .then(|| EffectShape { changes_z: effects.changes_z(), reflectivities: reflectivities.as_ref() }),
            compute_raster: range_table.as_ref(),
            several_draws: draws.len() > 1,
            from_host: host_view.is_some(),
            witnesses: pinhole.and_then(|(_, witnesses)| witnesses),
            rig_compute: pinhole.filter(|_| compute).map(|_| (largest, draws.len())),
        };
        let slot = self.slot(&shape, "render")?;
        let coverage = slot
            .compute_views()
            .map(|views| match draws.len() {
                1 => self.coverage_group(&[views], 1, largest),
                several => CoverageGroup::of_draws(ctx, self.pipelines.compute_raster()?, views, several, largest),
            })
            .transpose()?;
        let label_readback = Buffer::new(ctx, BufferDesc::readback(pixels * 4), "unshadowed labels readback")?;
        let z_readback = Buffer::new(ctx, BufferDesc::readback(pixels * 4), "z readback")?;
        let timestamps = Timestamps::new(ctx, PassClock::QUERIES, "pass timestamps")?;
        let mut clock = PassClock::new(&timestamps);
        let passes = self.passes((&scene.sensor, scanner), scene.shadow, effects, (compute, pinhole.is_some()))?;
        ctx.submit_and_wait("render", |cmd| {
            let mut enc = Encoder::new(ctx, cmd);
            let sink = Sink::Readback { label: &label_readback, z: &z_readback };
            clock.start(cmd);
            if let Some(group) = &coverage {
                passes.record_coverage(&mut enc, group, &[(&slot, &job)])?;
            }
            passes.record(&mut enc, &slot, &job, &sink, Some(&mut clock));
            Ok(())
        })?;

        let label_unshadowed: Vec<u32> = label_readback.read()?;
        let mut label = match slot.masked() {
            Some(m) => m.read()?,
            None => label_unshadowed.clone(),
        };
        let (losses, measured_z) = slot.effect_outputs();
        let z: Vec<f32> = match measured_z {
            Some(measured) => measured.read()?,
            None => {
                // Offsets from the local origin back to range-frame z, where a surface was hit.
                let z_origin = views.origin.z as f32;
                let mut z: Vec<f32> = z_readback.read()?;
                for (z, &label) in z.iter_mut().zip(&label_unshadowed) {
                    if label != 0 {
                        *z += z_origin;
                    }
                }
                z
            }
        };
        let losses: Vec<u32> = losses.map(|l| l.read()).transpose()?.unwrap_or_default();
        let reason: Vec<Reason> = (0..label.len())
            .map(|i| match (label_unshadowed[i], label[i], losses.get(i).copied().unwrap_or(0)) {
                (0, _, _) => Ok(Reason::NoSurface),
                (_, 0, _) => Ok(Reason::Shadow),
                (_, _, code) => Reason::from_code(code)
                    .ok_or_else(|| Error::Unsupported(format!("an effect pass wrote an unknown reason {code}"))),
            })
            .collect::<Result<_>>()?;
        for (label, reason) in label.iter_mut().zip(&reason) {
            if *reason != Reason::Valid {
                *label = 0;
            }
        }
        let timings = cast_time.into_iter().chain(clock.times()?).collect();
        // Where rays were cast, their witness bits; where a rig's label test ran, its own; else
        // the scanner's one witness, its camera: bit 0 where it could not see the point.
        let witness = match (cast_witness, slot.witness_bits()) {
            (Some(bits), _) => bits,
            (None, Some(bits)) => bits.read()?,
            (None, None) => reason.iter().map(|&r| u32::from(r == Reason::Shadow)).collect(),
        };
        Ok(RenderOutput {
            sensor: scene.sensor.clone(),
            shadow: scene.shadow,
            effects: scene.effects,
            shadow_pass: views.shadow.is_some() || casts_shadows(scene, scanner),
            // The scanner's views, or a rig's pinhole views, were rasterized.
            raster: (scanner.is_some() || pinhole.is_some()).then_some(if compute {
                Raster::Compute
            } else {
                Raster::Graphics
            }),
            label,
            label_unshadowed,
            z,
            reason,
            witness,
            timings,
        })
    }

    /// Renders a rig other than the paper's scanner: on the GPU, a pinhole reference view in
    /// shadow modes `none`, `label` and `depth` (pinhole/); on the CPU by exact ray casting
    /// (src/exact/rig.rs), any other, to the reference view and every witness in modes `exact`
    /// and `depth`, to the reference view alone in mode `none`. Its effects, where it names
    /// any, run as GPU passes over the image. Mode `label` on a rig whose label images the GPU
    /// cannot draw is refused by name (`pinhole::draws_rig`).
    fn render_rig(&self, scene: &Scene) -> Result<RenderOutput> {
        let sensor = &scene.sensor;
        let on_gpu = pinhole::draws_rig(sensor, scene.shadow.mode)?;
        let (width, height) = (sensor.width(), sensor.height());
        let triangles: u64 = scene.objects.iter().map(|o| o.mesh.triangles.len() as u64).sum();
        let pixels = u64::from(width) * u64::from(height);
        let views = Views::cast(width, height);
        let with_effects = !scene.effects.is_empty();
        if with_effects || on_gpu {
            self.check_pixel_buffers((width, height))?;
        }
        for (i, object) in scene.objects.iter().enumerate() {
            check_rigid(&object.pose, &format!("object {} ({})", i + 1, object.model_ref))?;
        }
        if on_gpu {
            return self.render_pinhole_rig(scene, &views);
        }
        let passes_bytes = if with_effects { slot_bytes((pixels, 0), &scene.effects, None, 1) } else { 0 };
        let cast_bytes = memory::exact_bytes(crate::exact::casters(sensor), triangles, pixels);
        self.ledger.check(format_args!("rendering a {width}×{height} image"), cast_bytes + passes_bytes)?;
        let cast = Cast::timed("exact rays", || render_rig_exact(scene))?;
        if with_effects {
            return self.render_views(scene, None, &views, &[], Source::Cast(cast));
        }
        Ok(cast_output(scene, cast))
    }
}

/// How a render's range view is made.
enum Source<'a> {
    /// By the scanner's passes, with the compute rasterizer where `compute` (in shadow mode
    /// `exact`, by rays cast on the CPU).
    Passes { compute: bool },
    /// Elsewhere, and copied in: rays cast on the CPU.
    Cast(Cast),
    /// By a rig's pinhole views, and their witnesses' label test where the set is given, with
    /// the compute rasterizer where `compute`.
    Pinhole { job: &'a PinholeJob, witnesses: Option<&'a WitnessSet>, compute: bool },
}

/// A range image cast on the CPU, with the time it took on the wall clock.
struct Cast {
    image: ExactImage,
    time: PassTime,
}

impl Cast {
    /// An image `make` casts on the CPU, timed as `name`.
    fn timed(name: &'static str, make: impl FnOnce() -> Result<ExactImage>) -> Result<Self> {
        let started = Instant::now();
        let image = make()?;
        Ok(Self { image, time: PassTime { name, ms: Some(started.elapsed().as_secs_f64() * 1e3), on_cpu: true } })
    }
}

/// Whether the scene's witnesses were tested outside the scanner's shadow pass: on the CPU in
/// shadow mode `exact`, and under a rig other than the paper's scanner (`scanner` `None`) in
/// modes `depth` (on the GPU under a pinhole reference view, else on the CPU) and `label` (on
/// the GPU: pinhole/).
fn casts_shadows(scene: &Scene, scanner: Option<&Scanner>) -> bool {
    matches!((scanner, scene.shadow.mode), (_, ShadowMode::Exact) | (None, ShadowMode::Depth | ShadowMode::Label))
}

/// A render of a rig cast on the CPU, without effects.
fn cast_output(scene: &Scene, cast: Cast) -> RenderOutput {
    let image = cast.image;
    let reason = image
        .label
        .iter()
        .zip(&image.shadowed)
        .map(|(&label, &shadowed)| match (label, shadowed) {
            (0, _) => Reason::NoSurface,
            (_, 0) => Reason::Shadow,
            _ => Reason::Valid,
        })
        .collect();
    RenderOutput {
        sensor: scene.sensor.clone(),
        shadow: scene.shadow,
        effects: scene.effects,
        shadow_pass: casts_shadows(scene, None),
        raster: None,
        label: image.shadowed,
        label_unshadowed: image.label,
        z: image.z.iter().map(|&z| z as f32).collect(),
        reason,
        witness: image.witness,
        timings: vec![cast.time],
    }
}
