//! What accuracy costs in time (`rangesynth accuracy`): every setting of the sweep
//! (settings.rs) on every scene (scenes.rs), measured against shadow mode `exact`, the
//! product's own ground truth (src/exact/):
//!
//! - wrong pixels: where validity or label differs from the exact image;
//! - the largest |Δz| over pixels valid in both with the same label (where labels differ the
//!   pixel is already wrong, and z belongs to another surface);
//! - the error of the verification score s of the correct hypothesis (the scene's first object
//!   in its true pose, bound to its own labels), |s − s_exact|, where s_exact verifies the same
//!   hypothesis in exact mode. The sensed image is the exact image segmented to that object:
//!   its pixels, shadows cast on it by the others included, and no others (N_i of the scores
//!   would otherwise count the table, and s5 reject every hypothesis);
//! - the wall time per pose of verifying a batch of poses (the pipelines already built; the
//!   fastest of a few runs, as other work on the machine only ever adds time), and one
//!   render's GPU time (exact mode's CPU ray casting included).
//!
//! Tessellation settings re-tessellate curved built-ins and are measured against the finest
//! tessellation ([`REFERENCE_TESSELLATION`]), which stands for the shape itself.

mod report;
mod scenes;
mod settings;

pub use report::{write_csv, write_plot, Summary, Table, CSV_HEADER};
pub use scenes::{retessellate, standard_scenes, SweepScene, REFERENCE_TESSELLATION};
pub use settings::{retessellated, sweep_settings, Setting};

use crate::error::Result;
use crate::io::RangeImage;
use crate::render::Raster;
use crate::shadow::{ShadowMode, ShadowSettings};
use crate::verify::{Hypothesis, SensedImage, Verifier, VerifySettings, DEFAULT_TOLERANCE};
use crate::{RenderOutput, Scene};
use glam::{DMat4, DVec3};
use std::collections::hash_map::{Entry, HashMap};
use std::time::Instant;

/// One setting measured on one scene: a line of `accuracy.csv`.
#[derive(Debug, Clone, PartialEq)]
pub struct Row {
    pub setting: String,
    pub scene: String,
    pub pixels: u64,
    pub wrong_pixels: u64,
    pub wrong_pct: f64,
    pub max_abs_dz: f64,
    pub score_abs_error: f64,
    pub ms_per_pose: f64,
    /// One render's pass times summed (GPU timestamps; exact mode's CPU rays on the wall
    /// clock); printed, not in the CSV.
    pub render_ms: f64,
    /// The setting re-tessellates curved built-ins (measured against the shape itself, on the
    /// scenes that have them); not in the CSV, whose setting name says it.
    pub tessellated: bool,
}

/// How a sweep measures.
#[derive(Debug, Clone, Copy)]
pub struct SweepOptions {
    /// Poses in the timed verification batch.
    pub poses: usize,
    /// Timed runs of the batch; the fastest counts.
    pub runs: usize,
    /// Sides or segments of curved built-ins in the reference of tessellation settings.
    pub reference_tessellation: u32,
}

/// The verifiers a sweep renders and scores with: the graphics path's, and the compute
/// rasterizer's where the device has it.
pub struct SweepVerifiers<'a> {
    pub graphics: &'a Verifier,
    pub compute: Option<&'a Verifier>,
}

impl SweepVerifiers<'_> {
    fn of(&self, raster: Raster) -> &Verifier {
        match (raster, self.compute) {
            (Raster::Compute, Some(v)) => v,
            _ => self.graphics,
        }
    }
}

/// The cells of a sweep, in order: (setting, scene) for every setting that applies to the
/// scene (tessellation settings only to scenes with curved built-ins).
pub fn cells(settings: &[Setting], scenes: &[SweepScene]) -> Result<Vec<(Setting, usize, Scene)>> {
    let mut cells = Vec::new();
    for setting in settings {
        for (index, s) in scenes.iter().enumerate() {
            let scene = match setting.tessellation {
                None => Some(s.scene.clone()),
                Some(n) => retessellate(&s.scene, n)?,
            };
            if let Some(scene) = scene {
                cells.push((*setting, index, Scene { shadow: setting.shadow, ..scene }));
            }
        }
    }
    Ok(cells)
}

/// Measures every cell; `progress` is told each cell's name when it starts.
pub fn sweep(
    verifiers: &SweepVerifiers,
    settings: &[Setting],
    scenes: &[SweepScene],
    options: SweepOptions,
    progress: &mut dyn FnMut(&str),
) -> Result<Vec<Row>> {
    let exact = ShadowSettings::of(ShadowMode::Exact);
    // The exact renders, by scene and by whether they are the reference tessellation's.
    let mut references: HashMap<(usize, bool), (RenderOutput, SensedImage, f64)> = HashMap::new();
    let mut rows = Vec::new();
    for (setting, index, scene) in cells(settings, scenes)? {
        let name = &scenes[index].name;
        progress(&format!("{} on {name}", setting.name()));
        let fine = setting.tessellation.is_some();
        if let Entry::Vacant(entry) = references.entry((index, fine)) {
            let base = &scenes[index].scene;
            let reference_scene = match fine {
                true => retessellate(base, options.reference_tessellation)?.unwrap_or_else(|| base.clone()),
                false => base.clone(),
            };
            let reference_scene = Scene { shadow: exact, ..reference_scene };
            let out = verifiers.graphics.renderer().render(&reference_scene)?;
            let sensed = part_sensed(&out, &reference_scene)?;
            let s_exact = correct_score(verifiers.graphics, &scenes[index], &reference_scene, &sensed)?;
            entry.insert((out, sensed, s_exact));
        }
        let (reference, sensed, s_exact) = &references[&(index, fine)];
        let verifier = verifiers.of(setting.raster);
        let out = verifier.renderer().render(&scene)?;
        let pixels = reference.label.len() as u64;
        let wrong_pixels = out.label.iter().zip(&reference.label).filter(|(a, b)| a != b).count() as u64;
        let max_abs_dz = (0..reference.label.len())
            .filter(|&i| out.label[i] != 0 && out.label[i] == reference.label[i])
            .map(|i| (f64::from(out.z[i]) - f64::from(reference.z[i])).abs())
            .fold(0.0, f64::max);
        let s = correct_score(verifier, &scenes[index], &scene, sensed)?;
        rows.push(Row {
            setting: setting.name(),
            scene: name.clone(),
            pixels,
            wrong_pixels,
            wrong_pct: 100.0 * wrong_pixels as f64 / pixels.max(1) as f64,
            max_abs_dz,
            score_abs_error: (s - s_exact).abs(),
            ms_per_pose: ms_per_pose(verifier, &scenes[index], &scene, sensed, options)?,
            render_ms: out.timings.iter().filter_map(|t| t.ms).sum(),
            tessellated: fine,
        });
    }
    Ok(rows)
}

/// The exact image `out` of `scene` as a sensor would see its first object alone: pixels of
/// other objects have no data.
fn part_sensed(out: &RenderOutput, scene: &Scene) -> Result<SensedImage> {
    let first = scene.label_bases()?[0] + 1;
    let part = first..first + scene.objects[0].mesh.surface_count();
    let mut image = RangeImage::from(out);
    for label in image.label.iter_mut().filter(|l| !part.contains(l)) {
        *label = 0;
    }
    SensedImage::new(&image, &scene.sensor)
}

/// The correct hypothesis of `scene` (its first object, bound to its own labels that the
/// sensed image shows), moved by `offset`.
fn correct_hypothesis(
    verifier: &Verifier,
    sweep_scene: &SweepScene,
    scene: &Scene,
    sensed: &SensedImage,
    offset: DVec3,
) -> Result<Hypothesis> {
    let part = &scene.objects[0];
    let label_base = scene.label_bases()?[0];
    let model = verifier.model(&part.model_ref, &sweep_scene.base_dir)?;
    let bindings = (1..=model.mesh.surface_count())
        .map(|s| (label_base + s, s))
        .filter(|(label, _)| sensed.segments.binary_search(label).is_ok())
        .collect();
    Ok(Hypothesis { id: "correct".into(), model, pose: DMat4::from_translation(offset) * part.pose, bindings })
}

fn verify_settings(scene: &Scene) -> VerifySettings {
    VerifySettings {
        sensor: scene.sensor.clone(),
        shadow: scene.shadow,
        effects: Default::default(),
        tolerance: DEFAULT_TOLERANCE,
        compare_shadow: false,
        chunk_size: 64,
    }
}

/// s of the correct hypothesis, verified with `scene`'s shadow settings.
fn correct_score(verifier: &Verifier, sweep_scene: &SweepScene, scene: &Scene, sensed: &SensedImage) -> Result<f64> {
    let hypothesis = correct_hypothesis(verifier, sweep_scene, scene, sensed, DVec3::ZERO)?;
    let results = verifier.verify(sensed, &verify_settings(scene), &[hypothesis], &mut |_| {})?;
    Ok(results[0].scores.s)
}

/// Wall milliseconds per pose of verifying `options.poses` poses of the correct hypothesis (each
/// moved a little), after one untimed pose has built whatever the setting needs: the fastest of
/// `options.runs` runs.
fn ms_per_pose(
    verifier: &Verifier,
    sweep_scene: &SweepScene,
    scene: &Scene,
    sensed: &SensedImage,
    options: SweepOptions,
) -> Result<f64> {
    let step = scene.sensor.require_scanner("the accuracy sweep")?.pitch[0] / 8.0;
    let batch: Vec<Hypothesis> = (0..options.poses.max(1))
        .map(|i| correct_hypothesis(verifier, sweep_scene, scene, sensed, DVec3::new(step * i as f64, 0.0, 0.0)))
        .collect::<Result<_>>()?;
    let settings = verify_settings(scene);
    verifier.verify(sensed, &settings, &batch[..1], &mut |_| {})?;
    let mut fastest = f64::INFINITY;
    for _ in 0..options.runs.max(1) {
        let started = Instant::now();
        verifier.verify(sensed, &settings, &batch, &mut |_| {})?;
        fastest = fastest.min(started.elapsed().as_secs_f64());
    }
    Ok(fastest * 1e3 / batch.len() as f64)
}
