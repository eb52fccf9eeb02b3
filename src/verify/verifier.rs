//! The verification entry point for an embedding daemon: a [`Verifier`] is created once,
//! loads each model once (cached by reference), and scores slices of hypotheses against a
//! sensed image. It is `Send + Sync`; every failure is an error value.
//!
//! A call splits its hypotheses into chunks, each recorded into one command buffer; a chunk's
//! size comes from the device (a sixteenth of its device-local heap, at most
//! [`CHUNK_COUNTS_BUDGET`]) and from the size of one hypothesis' counts, so a batch of any
//! length runs in bounded memory: the render-target slots and counts of the chunks in flight
//! (one, or three on a GPU), and the sensed image. A batch keeps as many slots as the verifier
//! asks for ([`Verifier::with_slots`]) and the memory budget holds, at least one. On a GPU,
//! three chunks are in flight at once, chunks recorded while the device runs another
//! (lanes.rs). In shadow mode `exact`, and under any rig but the paper's scanner that the GPU
//! does not draw, a chunk holds at most [`EXACT_CHUNK`] hypotheses, whose images are cast on
//! the CPU before it is submitted (docs/sensors-and-rigs.md, "Verifying under a rig").

use super::batch::{
    count_batch, default_slots, slot_memory, BatchCounts, BatchItem, BatchSettings, SensedBuffers, StageTimes,
};
use super::counts::{Counts, CountsLayout};
use super::lanes::{default_chunks_in_flight, in_lanes, lane_chunk_cap, MAX_CHUNKS_IN_FLIGHT};
use super::score_pass::ScorePass;
use super::scores::{score, Scores};
use super::sensed::{check_same_kind, SensedImage};
use crate::effects::Effects;
use crate::error::{Error, Result};
use crate::exact;
use crate::mesh::{Mesh, SurfaceChoice};
use crate::pose::check_rigid;
use crate::render::pinhole::{draws_rig, WitnessLayout};
use crate::render::HostView;
use crate::render::{rig_slot_bytes, slot_bytes, GpuMesh, Raster, Renderer, MAX_SLOTS};
use crate::scene::{load_model_as, model_form_key, ModelFormKey};
use crate::sensor::{Scanner, Sensor, View};
use crate::shadow::{ShadowMode, ShadowSettings};
use crate::untrusted::quoted;
use glam::{DMat4, DVec3};
use std::collections::HashMap;
use std::ops::Range;
use std::path::Path;
use std::sync::{Arc, Mutex};

/// Most hypotheses recorded into one command buffer.
pub const MAX_CHUNK: usize = 1024;
/// Most hypotheses in one chunk in shadow mode `exact`, whose images are cast on the CPU and
/// held until the chunk's submission: it bounds their memory.
pub const EXACT_CHUNK: usize = 16;

/// Most bytes of counts one chunk may hold (less on a device with a small heap).
pub const CHUNK_COUNTS_BUDGET: u64 = 64 << 20;

/// A model uploaded once and shared by every hypothesis that names it.
pub struct Model {
    pub mesh: Arc<Mesh>,
    gpu: GpuMesh,
    sphere: (DVec3, f64),
}

/// One hypothesis: a model in a pose, with bindings (scene label, model surface).
#[derive(Clone)]
pub struct Hypothesis {
    pub id: String,
    pub model: Arc<Model>,
    pub pose: DMat4,
    pub bindings: Vec<(u32, u32)>,
}

#[derive(Debug, Clone)]
pub struct VerifySettings {
    pub sensor: Sensor,
    pub shadow: ShadowSettings,
    /// The sensor effects applied to the synthetic images.
    pub effects: Effects,
    /// τ, model units.
    pub tolerance: f64,
    /// Also score the unshadowed image.
    pub compare_shadow: bool,
    /// Cap on hypotheses per submission (the device may impose a smaller one).
    pub chunk_size: usize,
}

#[derive(Debug, Clone)]
#[non_exhaustive]
pub struct Verification {
    pub id: String,
    pub counts: Counts,
    pub scores: Scores,
    /// With `compare_shadow`: the counts and scores without shadowing (where no shadow pass
    /// runs, mode `none` or θ = 0, the same as `counts` and `scores`).
    pub unshadowed: Option<(Counts, Scores)>,
    /// The rasterizer that rendered it (`Renderer::with_raster`; `auto` picks one a
    /// hypothesis): none where nothing was rendered, its footprint missing the image or shadow
    /// mode `exact` casting its rays on the host.
    pub raster: Option<Raster>,
}

impl Verification {
    /// The fewest bytes one holds: with no surfaces, bindings or notes.
    pub const LEAST_HELD_BYTES: u64 = size_of::<Verification>() as u64;

    /// Bytes it holds on the host, its lists and texts included: what a call that keeps every
    /// verification it returns ([`Verifier::verify`]) holds to the memory budget.
    pub fn held_bytes(&self) -> u64 {
        let unshadowed =
            self.unshadowed.as_ref().map_or(0, |(counts, scores)| counts.heap_bytes() + scores.heap_bytes());
        Self::LEAST_HELD_BYTES
            + self.id.capacity() as u64
            + self.counts.heap_bytes()
            + self.scores.heap_bytes()
            + unshadowed
    }
}

/// What a batch's checks settle for its recording.
#[derive(Clone, Copy)]
struct BatchPlan {
    /// 2 with `compare_shadow`, else 1.
    copies: usize,
    segments: u32,
    /// Most bytes of counts one chunk may hold on this device.
    counts_budget: u64,
    /// Render-target slots a batch keeps: as many as asked for that the budget holds.
    slots: usize,
    /// Chunks in flight at once (lanes.rs): as many as the verifier asks for whose slots and
    /// counts the budget holds, at least 1.
    lanes: usize,
    /// What the run holds while it verifies: the sensed image, and each lane's chunk.
    held_bytes: u64,
}

impl BatchPlan {
    fn layout(&self, h: &Hypothesis) -> CountsLayout {
        CountsLayout { surfaces: h.model.mesh.surface_count(), segments: self.segments }
    }

    fn counts_bytes(&self, h: &Hypothesis) -> u64 {
        (self.layout(h).words() * self.copies * 4) as u64
    }
}

pub struct Verifier {
    // Dropped before the renderer, whose context it was made on (it holds the context too).
    score_pass: ScorePass,
    renderer: Renderer,
    models: Mutex<HashMap<ModelFormKey, Arc<Model>>>,
    /// Most render-target slots a batch keeps (with_slots).
    slots: usize,
    /// Most chunks in flight at once (with_chunks_in_flight).
    chunks_in_flight: usize,
    /// GPU time by stage, where asked for (with_stage_times).
    stage_times: Option<StageTimes>,
}

// A daemon's threads, and the Python bindings' callers on several threads, share one verifier
// (and its renderer): a change that made either lose Send or Sync fails to compile here.
const _: fn() = || {
    fn shared<T: Send + Sync>() {}
    shared::<Verifier>();
    shared::<Renderer>();
};

impl Verifier {
    /// Fails only if the score pass's pipeline cannot be built on the renderer's device.
    pub fn new(renderer: Renderer) -> Result<Self> {
        let score_pass = ScorePass::new(renderer.context())?;
        let slots = default_slots(renderer.context());
        let chunks_in_flight = default_chunks_in_flight(renderer.context());
        let models = Mutex::new(HashMap::new());
        Ok(Self { score_pass, renderer, models, slots, chunks_in_flight, stage_times: None })
    }

    /// The same verifier, keeping up to `n` render-target slots a batch (clamped to 1 to
    /// [`MAX_SLOTS`]): a batch records its hypotheses in runs of that many, each stage of a
    /// run's passes behind one barrier. The default is 16 on a GPU, where a barrier drains the
    /// device, and 4 on a CPU device, where barriers cost next to nothing (batch.rs,
    /// `default_slots`). A batch keeps fewer where the memory budget holds fewer. The counts
    /// and scores are the same either way.
    pub fn with_slots(self, n: usize) -> Self {
        Self { slots: n.clamp(1, MAX_SLOTS), ..self }
    }

    /// Most render-target slots a batch keeps.
    pub fn slots(&self) -> usize {
        self.slots
    }

    /// The same verifier, keeping up to `n` chunks of a call in flight at once (clamped to 1
    /// to [`MAX_CHUNKS_IN_FLIGHT`]): with more than one, chunks are recorded while the device
    /// runs another (lanes.rs). The default is 3 on a GPU and 1 on a CPU device, whose
    /// "device" is the host's own cores: there the lanes only contend. Each needs the memory of
    /// a chunk; a call keeps as many as the budget holds. The counts and scores are the same
    /// either way.
    pub fn with_chunks_in_flight(self, n: usize) -> Self {
        Self { chunks_in_flight: n.clamp(1, MAX_CHUNKS_IN_FLIGHT), ..self }
    }

    /// Most chunks of a call in flight at once.
    pub fn chunks_in_flight(&self) -> usize {
        self.chunks_in_flight
    }

    /// The same verifier, timing its batches on the GPU stage by stage (a timestamp after each
    /// stage a run's hypotheses share: coverage set-up, coverage, large triangles, rasters,
    /// masks, effects, scores), for [`Verifier::take_stage_times`]: where a verification spends
    /// its device time (`bench_verify` prints it). The timestamps cost a little; off by default.
    pub fn with_stage_times(self) -> Self {
        Self { stage_times: Some(StageTimes::default()), ..self }
    }

    /// GPU milliseconds by stage, each summed over the hypotheses verified since the last
    /// call (by every thread), named by the stage's first timed pass, in the order first met;
    /// nothing unless the verifier times its stages, or on a device without timestamps.
    pub fn take_stage_times(&self) -> Vec<(&'static str, f64)> {
        self.stage_times.as_ref().map(StageTimes::take).unwrap_or_default()
    }

    /// This verifier as on a device whose square root errs by `ulps`, which the score pass
    /// corrects: for the test that stands in for such a device (NVIDIA's approximates it) on
    /// lavapipe, whose root is exact. Only with the feature `test-hooks`.
    #[cfg(feature = "test-hooks")]
    pub fn with_sqrt_error_for_tests(self, ulps: i32) -> Result<Self> {
        let score_pass = ScorePass::with_sqrt_error(self.renderer.context(), ulps)?;
        Ok(Self { score_pass, ..self })
    }

    pub fn renderer(&self) -> &Renderer {
        &self.renderer
    }

    /// The model named `reference` (a `builtin:` name, or an OBJ, PLY or STL path relative to
    /// `base_dir`), with its default surfaces and scale, loaded and uploaded on first use.
    pub fn model(&self, reference: &str, base_dir: &Path) -> Result<Arc<Model>> {
        self.model_as(reference, base_dir, SurfaceChoice::default(), 1.0)
    }

    /// [`Verifier::model`] with the surfaces `surfaces` asks for and its vertices multiplied by
    /// `scale` (model units to scene units: `load_model_as`); each form of a model is loaded
    /// and uploaded once.
    pub fn model_as(
        &self,
        reference: &str,
        base_dir: &Path,
        surfaces: SurfaceChoice,
        scale: f64,
    ) -> Result<Arc<Model>> {
        let key = model_form_key(reference, base_dir, surfaces, scale)?;
        if let Some(model) = self.models.lock().unwrap_or_else(|p| p.into_inner()).get(&key) {
            return Ok(model.clone());
        }
        let mesh = Arc::new(load_model_as(reference, base_dir, self.renderer.ledger(), surfaces, scale)?);
        let model = Arc::new(Model {
            gpu: GpuMesh::upload(self.renderer.context(), &mesh)?,
            sphere: mesh.bounding_sphere(),
            mesh,
        });
        Ok(self.models.lock().unwrap_or_else(|p| p.into_inner()).entry(key).or_insert(model).clone())
    }

    /// A model of a mesh the caller built (not a file: the Python bindings' `Mesh`), uploaded
    /// now and not kept: the caller keeps the model for as many calls as it likes.
    pub fn model_of_mesh(&self, mesh: Arc<Mesh>) -> Result<Arc<Model>> {
        let gpu = GpuMesh::upload(self.renderer.context(), &mesh)?;
        Ok(Arc::new(Model { gpu, sphere: mesh.bounding_sphere(), mesh }))
    }

    /// Checks everything [`Verifier::verify_each`] would refuse before it runs — the settings,
    /// each hypothesis' bindings and views, and the memory the batch needs — without touching
    /// the GPU, so a caller can refuse a whole file before it writes anything. (What
    /// [`Verifier::verify`] gathers is held to the budget as it runs, on top of this.)
    pub fn check(&self, sensed: &SensedImage, settings: &VerifySettings, hypotheses: &[Hypothesis]) -> Result<()> {
        self.plan(sensed, settings, hypotheses).map(|_| ())
    }

    fn plan(&self, sensed: &SensedImage, settings: &VerifySettings, hypotheses: &[Hypothesis]) -> Result<BatchPlan> {
        settings.sensor.validate()?;
        let scanner = settings.sensor.scanner();
        settings.effects.validate()?;
        settings.effects.for_sensor(&settings.sensor)?;
        settings.shadow.validate()?;
        // Refuses mode `label` on a rig whose witnesses it cannot read, and what the GPU cannot
        // draw of a pinhole rig (views or witness bands too large).
        // Where the GPU draws the rig: its witnesses' images' pixels (0 without any).
        let mut rig_witness_pixels = None;
        if scanner.is_none() && draws_rig(&settings.sensor, settings.shadow.mode)? {
            if let View::Pinhole(reference) = &settings.sensor.reference {
                self.renderer.check_pinhole(reference)?;
                let max_side = self.renderer.context().max_view_side();
                let layout = WitnessLayout::new(max_side, &settings.sensor, &settings.shadow)?;
                rig_witness_pixels = Some(layout.as_ref().map_or(0, WitnessLayout::pixels));
            }
        }
        let (width, height) = (settings.sensor.width(), settings.sensor.height());
        if (sensed.width, sensed.height) != (width, height) {
            return Err(Error::Scene(format!(
                "the sensed image is {}×{} but the sensor is {width}×{height}",
                sensed.width, sensed.height
            )));
        }
        // The sensed image and the shadowed labels are buffers of a word a pixel.
        self.renderer.check_pixel_buffers((width, height))?;
        check_same_pixels(&sensed.view, &settings.sensor.reference)?;
        if !(settings.tolerance.is_finite() && settings.tolerance >= 0.0) {
            return Err(Error::Scene(format!("tolerance {} must be a finite number ≥ 0", settings.tolerance)));
        }
        for h in hypotheses {
            check_rigid(&h.pose, &format!("hypothesis {}", quoted(&h.id)))?;
            let surfaces = h.model.mesh.surface_count();
            if let Some(&(scene, surface)) = h.bindings.iter().find(|&&(s, m)| s == 0 || m == 0 || m > surfaces) {
                return Err(Error::Scene(format!(
                    "hypothesis {}: binding ({scene}, {surface}) names no surface of {} (surfaces 1..={surfaces})",
                    quoted(&h.id),
                    h.model.mesh.name
                )));
            }
        }
        let ctx = self.renderer.context();
        let counts_budget = CHUNK_COUNTS_BUDGET.min(ctx.device_local_heap_size() / 16);
        let mut plan = BatchPlan {
            copies: if settings.compare_shadow { 2 } else { 1 },
            segments: sensed.segments.len() as u32,
            counts_budget,
            slots: self.slots.min(hypotheses.len()).max(1),
            lanes: 1,
            held_bytes: 0,
        };
        let per_hypothesis = |h: &Hypothesis| plan.counts_bytes(h);
        if let Some(h) = hypotheses.iter().find(|h| per_hypothesis(h) > counts_budget) {
            return Err(Error::Scene(format!(
                "hypothesis {}: counting {} segments against {} surfaces needs {} MiB, more than the {} MiB a batch may use",
                quoted(&h.id),
                sensed.segments.len(),
                h.model.mesh.surface_count(),
                per_hypothesis(h) >> 20,
                counts_budget >> 20
            )));
        }
        let posed = hypotheses.iter().map(|h| {
            (format!("hypothesis {}", quoted(&h.id)), (h.pose.transform_point3(h.model.sphere.0), h.model.sphere.1))
        });
        let max_triangles = hypotheses.iter().map(|h| h.model.mesh.triangles.len() as u64).max().unwrap_or(0);
        let pixels = u64::from(width) * u64::from(height);
        let per_slot = match &scanner {
            Some(scanner) => {
                slot_memory(&self.renderer, scanner, &settings.shadow, &settings.effects, posed, max_triangles)?
            }
            None => match rig_witness_pixels {
                Some(witness_pixels) => {
                    // The compute rasterizer's words and queues, for the reference view and
                    // each witness's band (raster/compute/rig.rs).
                    let views = 1 + if witness_pixels > 0 { settings.sensor.witnesses.len() as u64 } else { 0 };
                    let compute = self.renderer.may_compute().then_some((max_triangles, views));
                    rig_slot_bytes((pixels, witness_pixels), &settings.effects, compute)
                }
                None => slot_bytes((pixels, 0), &settings.effects, None, 1),
            },
        };
        let counts = hypotheses.iter().map(per_hypothesis).sum::<u64>().min(counts_budget);
        // Images cast on the CPU (shadow mode `exact`, and any rig but the scanner): one
        // chunk's, and the casters of one hypothesis.
        let exact_bytes = match casts_on_cpu(scanner.as_ref(), &settings.sensor, settings.shadow.mode)? {
            true => {
                let images = hypotheses.len().min(EXACT_CHUNK) as u64;
                let casters = exact::casters(&settings.sensor);
                images * (HostView::BYTES_PER_PIXEL + exact::BYTES_PER_PIXEL) * pixels
                    + max_triangles * casters * exact::CASTER_BYTES_PER_TRIANGLE
            }
            false => 0,
        };
        // The sensed image on the host and the GPU; and a chunk's: its counts with their
        // readback, its exact images and its slots, as many as the budget holds, up to those
        // asked for. As many chunks in flight (lanes.rs) as asked for and the budget holds.
        let sensed_bytes = (SensedImage::HOST_BYTES_PER_PIXEL + SensedImage::GPU_BYTES_PER_PIXEL) * pixels;
        let chunk_bytes = 2 * counts + exact_bytes;
        let ledger = self.renderer.ledger();
        let available = ledger.available();
        let holds = available.saturating_sub(sensed_bytes + chunk_bytes) / per_slot.max(1);
        plan.slots = plan.slots.min(usize::try_from(holds).unwrap_or(usize::MAX)).max(1);
        let in_flight = chunk_bytes + per_slot * plan.slots as u64;
        let what = format_args!("verifying against a {width}×{height} image");
        ledger.check(what, sensed_bytes + in_flight)?;
        plan.lanes = (1..=self.chunks_in_flight)
            .rev()
            .find(|&lanes| sensed_bytes + lanes as u64 * in_flight <= available)
            .unwrap_or(1);
        plan.held_bytes = sensed_bytes + plan.lanes as u64 * in_flight;
        Ok(plan)
    }

    /// Scores every hypothesis against the sensed image, in order. `progress` is told how many
    /// hypotheses are done after each chunk. The verifications it gathers are held to the
    /// memory budget while it runs, with what the run holds (the slots it plans fit beside
    /// them): refused before anything runs where even the least each can hold would not fit,
    /// and stopped at the first chunk past it (a model of many surfaces holds counts a
    /// surface). [`Verifier::verify_each`] hands them on instead, holding a few chunks'.
    pub fn verify(
        &self,
        sensed: &SensedImage,
        settings: &VerifySettings,
        hypotheses: &[Hypothesis],
        progress: &mut dyn FnMut(usize),
    ) -> Result<Vec<Verification>> {
        self.verify_until(sensed, settings, hypotheses, &mut |done| {
            progress(done);
            Ok(())
        })
    }

    /// [`Verifier::verify`], whose `progress` may stop the call with an error (a caller's own
    /// callback that failed: Python's), which is returned.
    pub fn verify_until(
        &self,
        sensed: &SensedImage,
        settings: &VerifySettings,
        hypotheses: &[Hypothesis],
        progress: &mut dyn FnMut(usize) -> Result<()>,
    ) -> Result<Vec<Verification>> {
        let holding = |count: usize| format!("holding the verifications of {count} hypotheses");
        let least = (hypotheses.len() as u64).saturating_mul(Verification::LEAST_HELD_BYTES);
        let mut held = self.renderer.ledger().hold(holding(hypotheses.len()), least)?;
        let mut results = Vec::with_capacity(hypotheses.len());
        self.verify_each(sensed, settings, hypotheses, &mut |chunk| {
            let more: u64 = chunk.iter().map(|v| v.held_bytes() - Verification::LEAST_HELD_BYTES).sum();
            held.grow(holding(results.len() + chunk.len()), more)?;
            results.extend(chunk);
            progress(results.len())
        })?;
        Ok(results)
    }

    /// Scores every hypothesis against the sensed image, handing the verifications to `each`
    /// chunk by chunk, in order, as soon as a chunk and those before it are done: a caller that
    /// writes them out holds a few chunks' at a time at most (lanes.rs), however long the
    /// call, and the chunks in flight never wait for the results of a slice to be gathered.
    /// An error from `each` stops the call (no further chunk starts) and is returned.
    pub fn verify_each(
        &self,
        sensed: &SensedImage,
        settings: &VerifySettings,
        hypotheses: &[Hypothesis],
        each: &mut dyn FnMut(Vec<Verification>) -> Result<()>,
    ) -> Result<()> {
        let plan = self.plan(sensed, settings, hypotheses)?;
        // Held while it runs, so that what a caller gathers meanwhile (Verifier::verify_until)
        // and other calls on this verifier's budget count on top of it.
        let (width, height) = (settings.sensor.width(), settings.sensor.height());
        let _running =
            self.renderer.ledger().hold(format_args!("verifying against a {width}×{height} image"), plan.held_bytes)?;
        let scanner = settings.sensor.scanner();
        let ctx = self.renderer.context();
        let (copies, counts_budget) = (plan.copies, plan.counts_budget);
        let layout = |h: &Hypothesis| plan.layout(h);
        let per_hypothesis = |h: &Hypothesis| plan.counts_bytes(h);
        let on_gpu = sensed.on_gpu(ctx)?;
        let batch = BatchSettings {
            sensor: &settings.sensor,
            scanner: scanner.as_ref(),
            shadow: settings.shadow,
            effects: &settings.effects,
            tolerance: settings.tolerance as f32,
            blocks: sensed.blocks,
            sensed: SensedBuffers { pixels: &on_gpu.pixels, segment_count: sensed.segments.len() as u32 },
            slots: plan.slots,
            stage_times: self.stage_times.as_ref(),
        };
        let chunk_cap = match casts_on_cpu(scanner.as_ref(), &settings.sensor, settings.shadow.mode)? {
            true => settings.chunk_size.clamp(1, EXACT_CHUNK),
            false => settings.chunk_size.clamp(1, MAX_CHUNK),
        };
        // Each chunk as long as its cap (in lanes, shorter: lane_chunk_cap) and the counts
        // budget allow.
        let mut chunks: Vec<Range<usize>> = Vec::new();
        let mut start = 0;
        while start < hypotheses.len() {
            let cap = match plan.lanes {
                1 => chunk_cap,
                lanes => lane_chunk_cap(chunk_cap, hypotheses.len(), lanes, chunks.len()),
            };
            let mut end = start;
            let mut bytes = 0;
            while end < hypotheses.len()
                && end - start < cap
                && bytes + per_hypothesis(&hypotheses[end]) <= counts_budget
            {
                bytes += per_hypothesis(&hypotheses[end]);
                end += 1;
            }
            chunks.push(start..end);
            start = end;
        }
        let shadow_pass = match &scanner {
            Some(scanner) => settings.shadow.mode.shadows(scanner.theta_deg),
            None => settings.shadow.mode != ShadowMode::None && !settings.sensor.witnesses.is_empty(),
        };
        let verify_chunk = |range: Range<usize>| -> Result<Vec<Verification>> {
            let chunk = &hypotheses[range];
            let mut offset = 0;
            let items: Vec<BatchItem> = chunk
                .iter()
                .map(|h| {
                    let words = layout(h).words();
                    let item = BatchItem {
                        mesh: &h.model.gpu,
                        sphere: h.model.sphere,
                        pose: h.pose,
                        surfaces: h.model.mesh.surface_count(),
                        model: &h.model.mesh,
                        counts_offset: offset,
                        unshadowed_offset: settings.compare_shadow.then_some(offset + words),
                        counts_words: words * copies,
                    };
                    offset += words * copies;
                    item
                })
                .collect();
            let BatchCounts { words, rasters } = count_batch(&self.renderer, &self.score_pass, &batch, &items, offset)?;
            let verified = chunk.iter().zip(&items).zip(rasters).map(|((h, item), raster)| {
                let l = layout(h);
                let counts = l.decode(&words[item.counts_offset..item.counts_offset + l.words()], sensed.valid);
                let scores = score(&counts, sensed, &h.bindings);
                let unshadowed = match item.unshadowed_offset {
                    Some(o) if shadow_pass => {
                        let c = l.decode(&words[o..o + l.words()], sensed.valid);
                        let s = score(&c, sensed, &h.bindings);
                        Some((c, s))
                    }
                    Some(_) => Some((counts.clone(), scores.clone())),
                    None => None,
                };
                Verification { id: h.id.clone(), counts, scores, unshadowed, raster }
            });
            Ok(verified.collect())
        };
        // Several chunks in flight where there are several and the budget holds them (lanes.rs).
        if plan.lanes > 1 && chunks.len() > 1 {
            let lanes = plan.lanes.min(chunks.len());
            in_lanes(lanes, chunks.len(), |chunk| verify_chunk(chunks[chunk].clone()), |_, verified| each(verified))
        } else {
            chunks.iter().try_for_each(|range| each(verify_chunk(range.clone())?))
        }
    }
}

/// Whether a verification's images are cast on the CPU: in shadow mode `exact`, and under any
/// rig but the paper's scanner (`scanner` `None`) that the GPU does not draw
/// (`pinhole::draws_rig`).
fn casts_on_cpu(scanner: Option<&Scanner>, sensor: &Sensor, mode: ShadowMode) -> Result<bool> {
    Ok(match scanner {
        Some(_) => mode == ShadowMode::Exact,
        None => !draws_rig(sensor, mode)?,
    })
}

/// Refuses a sensor whose pixels are not those the sensed image was measured in: another
/// kind of view, another orthographic pitch, other pinhole intrinsics (its size is checked
/// before).
fn check_same_pixels(sensed: &View, sensor: &View) -> Result<()> {
    check_same_kind(sensed, sensor)?;
    let refuse = |what: String| Err(Error::Scene(format!("the sensed image {what}")));
    match (sensed, sensor) {
        (View::Orthographic(a), View::Orthographic(b)) if a.pitch != b.pitch => {
            refuse(format!("was measured at pitch {:?} but the sensor has pitch {:?}", a.pitch, b.pitch))
        }
        (View::Pinhole(a), View::Pinhole(b)) if a.intrinsics != b.intrinsics => {
            refuse(format!("was measured with intrinsics {:?} but the sensor has {:?}", a.intrinsics, b.intrinsics))
        }
        _ => Ok(()),
    }
}
