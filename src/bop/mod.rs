//! Scoring the pose estimates of a BOP results file against a BOP dataset's depth images under
//! the rig of the sensor that took them (docs/bop.md): each row's estimate is rendered under the
//! rig, with the image's own intrinsics, and given
//!
//! - the depth-only scores (depth_scores.rs), against the image's depth;
//! - where the dataset has the image's ground truth for the object, VSD (vsd.rs) as the BOP
//!   toolkit defines it, the estimate and the ground truth rendered alone; and VSD again with
//!   both rendered under the rig, so that what the sensor could not have measured (its
//!   projector's shadows on the model, what its other cameras do not see) is not rendered as
//!   visible surface.
//!
//! The images are cast on the CPU in f64 (src/exact/rig.rs; shadow mode `exact`), or drawn on
//! the GPU (src/render/pinhole/; modes `label` and `none`), each within the model's footprint,
//! as `verify` makes a rig's hypotheses. Rows are scored in order, one image's data kept while
//! its rows follow one another, their images made together (on the GPU, in one submission), and
//! each image's memory given back to the run's budget when the next begins.

mod dataset;
mod depth_scores;
mod results;
mod vsd;

pub use dataset::{Camera, Dataset, GtPose, SceneFiles};
pub use depth_scores::{depth_scores, DepthScores, Prediction};
pub use results::{parse_results, pose_from_bop, ResultRow, RESULTS_HEADER, ROTATION_TOLERANCE};
pub use vsd::{tolerances, vsd_errors, vsd_summary, VsdView};

use crate::error::{Error, Result};
use crate::exact::{self, render_rig, ExactImage, ExactObject};
use crate::io::read_depth_png;
use crate::limits::Ledger;
use crate::mesh::{Mesh, Solidity, SurfaceChoice, SurfaceRule};
use crate::render::pinhole::draws_rig;
use crate::render::{DrawnAlone, Renderer};
use crate::scene::load_model_as;
use crate::sensor::{Intrinsics, Pinhole, PixelRect, Sensor, View};
use crate::shadow::ShadowSettings;
use glam::DMat4;
use std::collections::HashMap;
use std::sync::Arc;

/// The columns a scores file adds to the results file's.
pub const SCORE_COLUMNS: [&str; 8] = [
    "inlier",
    "violation",
    "explained_holes",
    "depth_score",
    "vsd",
    "vsd_recall",
    "vsd_shadowed",
    "vsd_shadowed_recall",
];

/// Whether two rows are of the same image: a run of such rows shares the image's data
/// (`rows.chunk_by(same_image)`).
pub fn same_image(a: &ResultRow, b: &ResultRow) -> bool {
    (a.scene_id, a.im_id) == (b.scene_id, b.im_id)
}

/// Pixels added around a model's footprint where its image is cast.
const FOOTPRINT_MARGIN: u32 = 2;

/// One row's scores; the VSD pairs (mean error, recall) are `None` where the dataset has no
/// ground truth for the row's object in its image.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RowScores {
    pub depth: DepthScores,
    pub vsd: Option<(f64, f64)>,
    pub vsd_shadowed: Option<(f64, f64)>,
}

impl RowScores {
    /// The row's cells for [`SCORE_COLUMNS`]: empty where a score does not apply.
    pub fn cells(&self) -> Vec<String> {
        let number = |v: Option<f64>| v.map(|v| v.to_string()).unwrap_or_default();
        let d = &self.depth;
        [
            Some(d.inlier),
            Some(d.violation),
            d.explained_holes,
            Some(d.depth_score),
            self.vsd.map(|v| v.0),
            self.vsd.map(|v| v.1),
            self.vsd_shadowed.map(|v| v.0),
            self.vsd_shadowed.map(|v| v.1),
        ]
        .map(number)
        .to_vec()
    }
}

/// How rows are scored: the rig (its reference view's intrinsics and size are each image's),
/// the tolerance δ (mm) of the depth-only scores and of VSD's visibility test, and the
/// shadow settings the rig's images are made with: mode `exact` cast on the CPU, modes
/// `label` and `none` drawn on the GPU (which the scorer is then given).
pub struct BopSettings {
    pub rig: Sensor,
    pub delta: f64,
    pub shadow: ShadowSettings,
}

/// Most rows of one image whose images the GPU draws together (casting them on the CPU
/// gains nothing from it: there a row's image is made, scored and dropped before the next).
const ROWS_TOGETHER: usize = 16;

/// A model's image: depth (mm) where the reference view meets it, 0 elsewhere; the same where
/// every witness sees the point, 0 where one does not.
struct Rendering {
    depth: Vec<f64>,
    measured_depth: Vec<f64>,
}

impl Rendering {
    /// Bytes one holds a pixel of the image.
    const BYTES_PER_PIXEL: u64 = 16;

    /// From labels before and after shadowing and depths, a word a pixel each.
    fn of(label: &[u32], shadowed: &[u32], z: impl Iterator<Item = f64> + Clone) -> Self {
        let kept = |labels: &[u32]| labels.iter().zip(z.clone()).map(|(&l, z)| if l != 0 { z } else { 0.0 }).collect();
        Self { depth: kept(label), measured_depth: kept(shadowed) }
    }

    fn cast(image: ExactImage) -> Self {
        Self::of(&image.label, &image.shadowed, image.z.iter().copied())
    }

    fn drawn(image: DrawnAlone) -> Self {
        Self::of(&image.label, &image.shadowed, image.z.iter().map(|&z| f64::from(z)))
    }
}

/// The image the rows of one (scene, image) share.
struct ImageData {
    key: (u32, u32),
    sensor: Sensor,
    intrinsics: Intrinsics,
    /// Sensed depth, mm (0: no measurement).
    sensed: Vec<f64>,
    ground_truth: Vec<GtPose>,
    /// Each ground-truth instance's rendering, made when a row first needs it.
    truth_renderings: HashMap<usize, Arc<Rendering>>,
    /// Bytes charged to the run for the image, given back when the next begins.
    bytes: u64,
}

/// Scores rows of a results file in order, keeping what consecutive rows share.
pub struct BopScorer<'a> {
    dataset: &'a Dataset,
    settings: &'a BopSettings,
    /// Where the rig's images are drawn on the GPU (shadow modes `label` and `none`).
    renderer: Option<&'a Renderer>,
    /// The rig's reference view, whose intrinsics and size each image replaces.
    reference: Pinhole,
    ledger: &'a Ledger,
    scenes: HashMap<u32, Arc<SceneFiles>>,
    models: HashMap<u32, Arc<Mesh>>,
    /// Whether each loaded model bounds a solid, which exact casting culls by
    /// (src/exact/mod.rs), found once a model: keyed by the model's address, which names one
    /// model for as long as the scorer lives, as `models` keeps every model it loads (were it
    /// to drop one, this must drop its entry too).
    solidities: HashMap<usize, Solidity>,
    image: Option<ImageData>,
}

impl<'a> BopScorer<'a> {
    /// A scorer of `dataset`'s rows; `renderer` draws the rig's images where the shadow mode
    /// is the GPU's (`label`, `none`), and must be given then.
    pub fn new(
        dataset: &'a Dataset,
        settings: &'a BopSettings,
        renderer: Option<&'a Renderer>,
        ledger: &'a Ledger,
    ) -> Result<Self> {
        settings.shadow.validate()?;
        // Refuses a rig whose witnesses the label test cannot read.
        let on_gpu = draws_rig(&settings.rig, settings.shadow.mode)?;
        if on_gpu && renderer.is_none() {
            return Err(Error::Unsupported(format!(
                "shadow mode \"{}\" draws the rig's images on the GPU: the scorer needs a renderer",
                settings.shadow.mode.as_str()
            )));
        }
        let View::Pinhole(reference) = settings.rig.reference else {
            return Err(Error::Scene(format!(
                "the rig's reference view is {}; BOP depth images are a pinhole camera's (kind = \"pinhole\")",
                settings.rig.reference.kind()
            )));
        };
        if !(settings.delta.is_finite() && settings.delta >= 0.0) {
            return Err(Error::Scene(format!("δ = {} must be a finite number ≥ 0", settings.delta)));
        }
        let renderer = renderer.filter(|_| on_gpu);
        Ok(Self {
            dataset,
            settings,
            renderer,
            reference,
            ledger,
            scenes: HashMap::new(),
            models: HashMap::new(),
            solidities: HashMap::new(),
            image: None,
        })
    }

    fn scene(&mut self, scene_id: u32) -> Result<Arc<SceneFiles>> {
        if let Some(files) = self.scenes.get(&scene_id) {
            return Ok(files.clone());
        }
        let files = Arc::new(self.dataset.scene(scene_id, self.ledger)?);
        self.scenes.insert(scene_id, files.clone());
        Ok(files)
    }

    fn model(&mut self, obj_id: u32) -> Result<Arc<Mesh>> {
        if let Some(mesh) = self.models.get(&obj_id) {
            return Ok(mesh.clone());
        }
        let path = self.dataset.model_path(obj_id)?;
        let reference = path.to_string_lossy();
        // One surface: the scores read depth alone.
        let whole = SurfaceChoice { rule: Some(SurfaceRule::Whole), ..SurfaceChoice::default() };
        let mesh = Arc::new(load_model_as(&reference, std::path::Path::new("."), self.ledger, whole, 1.0)?);
        self.models.insert(obj_id, mesh.clone());
        // Only exact casting reads it (the GPU's upload finds it again).
        if self.renderer.is_none() {
            self.solidities.insert(Arc::as_ptr(&mesh) as usize, mesh.solidity());
        }
        Ok(mesh)
    }

    /// Makes the row's image the current one: its camera, depth and ground truth.
    fn image(&mut self, scene_id: u32, im_id: u32) -> Result<&mut ImageData> {
        if self.image.as_ref().is_some_and(|image| image.key == (scene_id, im_id)) {
            return Ok(self.image.as_mut().expect("checked above"));
        }
        if let Some(previous) = self.image.take() {
            self.ledger.release(previous.bytes);
        }
        let files = self.scene(scene_id)?;
        let camera = self.dataset.camera(&files, scene_id, im_id)?;
        let path = self.dataset.depth_path(scene_id, im_id);
        // What the image takes from here on is given back when the next image begins, or at
        // once if this one fails (the scorer charges its ledger from one thread).
        let held = self.ledger.held();
        let taken = |ledger: &Ledger| ledger.held().saturating_sub(held);
        let read = || -> Result<crate::io::DepthPng> {
            let png = read_depth_png(&path, self.ledger)?;
            let pixels = u64::from(png.width) * u64::from(png.height);
            self.ledger.charge(format_args!("the depth of {}", path.display()), pixels * 8)?;
            Ok(png)
        };
        let png = read().inspect_err(|_| self.ledger.release(taken(self.ledger)))?;
        // As the BOP toolkit reads it: the value times the scale, in f32.
        let scale = camera.depth_scale as f32;
        let sensed = png.values.iter().map(|&v| f64::from(f32::from(v) * scale)).collect();
        let intrinsics = camera.intrinsics((png.width, png.height));
        let reference = View::Pinhole(Pinhole { intrinsics, ..self.reference });
        let sensor = Sensor { reference, ..self.settings.rig.clone() };
        if let Err(e) = sensor.validate() {
            self.ledger.release(taken(self.ledger));
            return Err(e.concerning(&format!("scene {scene_id}, image {im_id}")));
        }
        let ground_truth = files.gt.get(&im_id).cloned().unwrap_or_default();
        let bytes = taken(self.ledger);
        Ok(self.image.insert(ImageData {
            key: (scene_id, im_id),
            sensor,
            intrinsics,
            sensed,
            ground_truth,
            truth_renderings: HashMap::new(),
            bytes,
        }))
    }

    /// The images of `models` (a mesh and its pose each) under the image's rig, each within
    /// its footprint: drawn on the GPU together, or cast on the CPU one by one.
    /// `subject(i)` names model i in errors.
    fn renderings(
        &self,
        sensor: &Sensor,
        models: &[(Arc<Mesh>, DMat4)],
        subject: &dyn Fn(usize) -> String,
    ) -> Result<Vec<Rendering>> {
        if let Some(renderer) = self.renderer {
            // Their two depth images each, made from the drawn images (which draw_alone checks).
            let pixels = u64::from(sensor.width()) * u64::from(sensor.height());
            let renderings = Rendering::BYTES_PER_PIXEL * pixels * models.len() as u64;
            self.ledger.check(format_args!("{} renderings of a rig's images", models.len()), renderings)?;
            let drawn = renderer.draw_alone(sensor, &self.settings.shadow, models, subject)?;
            return Ok(drawn.into_iter().map(Rendering::drawn).collect());
        }
        let (width, height) = (sensor.width(), sensor.height());
        let pixels = u64::from(width) * u64::from(height);
        let casters = exact::casters(sensor);
        // Each image cast is checked on top of those cast before it, which are held with it.
        let mut made = self.ledger.hold(format_args!("{} renderings of a rig's images", models.len()), 0)?;
        (0..)
            .zip(models)
            .map(|(i, (mesh, pose))| {
                let about = |e: Error| e.concerning(&subject(i));
                let triangles = mesh.triangles.len() as u64;
                // The image cast, and the rendering made from it while it is alive.
                let image_bytes = (exact::BYTES_PER_PIXEL + Rendering::BYTES_PER_PIXEL) * pixels;
                self.ledger
                    .check(
                        format_args!("casting a {width}×{height} image"),
                        image_bytes + casters * triangles * exact::CASTER_BYTES_PER_TRIANGLE,
                    )
                    .map_err(about)?;
                let (centre, radius) = mesh.bounding_sphere();
                let footprint = sensor.reference.footprint(pose.transform_point3(centre), radius, FOOTPRINT_MARGIN);
                let footprint = footprint.unwrap_or(PixelRect::EMPTY);
                let solidity = self.solidities.get(&(Arc::as_ptr(mesh) as usize)).copied().unwrap_or(Solidity::Open);
                let object = ExactObject { mesh, pose: *pose, label_base: 0, solidity };
                let image = render_rig(sensor, &[object], self.settings.shadow.mode, footprint).map_err(about)?;
                made.grow(format_args!("casting a {width}×{height} image"), Rendering::BYTES_PER_PIXEL * pixels)
                    .map_err(about)?;
                Ok(Rendering::cast(image))
            })
            .collect()
    }

    /// Scores rows in order; the rows of one image that follow one another have their images
    /// made together (on the GPU, in one batch), up to 16 at a time.
    pub fn score_rows(&mut self, rows: &[ResultRow]) -> Result<Vec<RowScores>> {
        let mut scores = Vec::with_capacity(rows.len());
        let together = if self.renderer.is_some() { ROWS_TOGETHER } else { 1 };
        for together in rows.chunk_by(same_image).flat_map(|run| run.chunks(together)) {
            scores.extend(self.score_together(together)?);
        }
        Ok(scores)
    }

    /// Scores rows of one image, their images (and those of the ground truth they need that
    /// the image has not made yet) made together.
    fn score_together(&mut self, rows: &[ResultRow]) -> Result<Vec<RowScores>> {
        let Some(first) = rows.first() else {
            return Ok(Vec::new());
        };
        let subject = |row: &ResultRow| format!("scene {}, image {}, object {}", row.scene_id, row.im_id, row.obj_id);
        let meshes: Vec<Arc<Mesh>> = rows.iter().map(|row| self.model(row.obj_id)).collect::<Result<_>>()?;
        self.image(first.scene_id, first.im_id)?;
        let image = self.image.as_ref().expect("made above");
        // Each ground-truth instance of the rows' objects not yet made, made once for the
        // image's rows.
        let needed: Vec<(usize, u32, DMat4)> = (0..image.ground_truth.len())
            .filter(|k| !image.truth_renderings.contains_key(k))
            .filter(|&k| rows.iter().any(|row| row.obj_id == image.ground_truth[k].obj_id))
            .map(|k| (k, image.ground_truth[k].obj_id, image.ground_truth[k].pose))
            .collect();
        let mut models: Vec<(Arc<Mesh>, DMat4)> = meshes.iter().cloned().zip(rows.iter().map(|r| r.pose)).collect();
        for &(_, obj_id, pose) in &needed {
            models.push((self.model(obj_id)?, pose));
        }
        let image = self.image.as_ref().expect("made above");
        let named = |i: usize| match rows.get(i) {
            Some(row) => subject(row),
            None => format!("{}: its ground truth", subject(first)),
        };
        let mut made = self.renderings(&image.sensor, &models, &named)?;
        let truths = made.split_off(rows.len());
        // The rows' own images, held while they are scored (the truths are kept, below).
        let estimate_bytes = made.iter().map(|r| Rendering::BYTES_PER_PIXEL * r.depth.len() as u64).sum();
        let _estimates = self.ledger.hold(format_args!("{}: the rows' renderings", subject(first)), estimate_bytes)?;
        for ((k, ..), truth) in needed.into_iter().zip(truths) {
            // Kept while the image's rows last: its two depth images.
            let bytes = Rendering::BYTES_PER_PIXEL * truth.depth.len() as u64;
            self.ledger.charge(format_args!("{}: a ground-truth rendering", subject(first)), bytes)?;
            let image = self.image.as_mut().expect("made above");
            image.bytes += bytes;
            image.truth_renderings.insert(k, Arc::new(truth));
        }
        rows.iter().zip(made).map(|(row, estimate)| self.score_with(row, &estimate)).collect()
    }

    /// Scores one row of the current image, whose estimate's image is `estimate`, against
    /// the ground truth the image has made.
    fn score_with(&self, row: &ResultRow, estimate: &Rendering) -> Result<RowScores> {
        let diameter = self.dataset.diameter(row.obj_id)?;
        let image = self.image.as_ref().expect("the row's image is made");
        let measured: Vec<bool> = estimate.measured_depth.iter().map(|&d| d > 0.0).collect();
        let prediction = Prediction { depth: &estimate.depth, measured: &measured };
        let depth = depth_scores(&prediction, &image.sensed, self.settings.delta);
        // Each ground-truth instance of the object.
        let truths: Vec<&Rendering> = (0..image.ground_truth.len())
            .filter(|&k| image.ground_truth[k].obj_id == row.obj_id)
            .map(|k| image.truth_renderings.get(&k).map(Arc::as_ref).expect("made with the row's image"))
            .collect();
        let p = image.intrinsics;
        let view =
            VsdView { width: p.width as usize, height: p.height as usize, fx: p.fx, fy: p.fy, cx: p.cx, cy: p.cy };
        let delta = self.settings.delta;
        let vsd_of = |truth: &Rendering, of: fn(&Rendering) -> &[f64]| -> Result<(f64, f64)> {
            Ok(vsd_summary(&vsd_errors(&view, &image.sensed, of(estimate), of(truth), diameter, delta)?))
        };
        let alone: fn(&Rendering) -> &[f64] = |r| r.depth.as_slice();
        let under_rig: fn(&Rendering) -> &[f64] = |r| r.measured_depth.as_slice();
        // The instance the estimate matches best, by the lowest mean error rendered alone; both
        // columns are of that one instance.
        let mut best: Option<((f64, f64), &Rendering)> = None;
        for &truth in &truths {
            let scores = vsd_of(truth, alone)?;
            if best.is_none_or(|(b, _)| scores.0 < b.0) {
                best = Some((scores, truth));
            }
        }
        let vsd_shadowed = best.map(|(_, truth)| vsd_of(truth, under_rig)).transpose()?;
        Ok(RowScores { depth, vsd: best.map(|(scores, _)| scores), vsd_shadowed })
    }
}
