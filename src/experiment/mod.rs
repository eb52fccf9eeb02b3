//! The paper's experiment on a synthetic benchmark (`rangesynth experiment`): does shadowing
//! separate correct from incorrect hypotheses?
//!
//! Each model (parts.rs) is placed on a table in several random poses; each view is rendered
//! as the "sensed" image by a more realistic sensor than the verifier assumes (depth-mode
//! shadows, which match exact ray casting, axial noise, grazing and mixed-pixel edge losses,
//! at the paper's θ = 45°; the table below the working volume), and written as `views/<view>/range.exr`. Its header records the
//! sensor and shadow settings but not the effects, as a real scanner's image would not say how
//! it was degraded. A recognizer's hypotheses (hypotheses.rs) go to
//! `views/<view>/hypotheses.json`, which asks for the paper's label test and no effects, and are
//! verified exactly as `rangesynth verify hypotheses.json --scene range.exr --compare-shadow`
//! verifies them: both files are read back from disk, and the lines of `scores.jsonl` are the
//! command's. The figures (stats.rs) go to `table.md`, `summary.json` and `scores.png`.
//!
//! The directory is one set (io/atomic.rs): the run writes it whole beside `out`, every file
//! read back from there, and swaps it in at the end, so `out` holds one run's files, never
//! views of two runs (or of a larger earlier run) beside another's summary. A failed or killed
//! run leaves the previous set as it was.

mod hypotheses;
mod parts;
mod stats;

pub use hypotheses::{CORRECT, CORRECT_PER_VIEW};
pub use parts::{generated_parts, write_obj, BUILTIN_PARTS};
pub use stats::{auc, summarise, table_markdown, write_plot, ClassSummary, Flips, Scored, Summary};

use crate::effects::{Edges, Effects, Grazing, Noise, WorkingVolume};
use crate::error::{Error, Result};
use crate::io::{read_range_image, write_atomically, write_range_image, RangeImage, StagedSet};
use crate::limits::{Ledger, MemoryBudget};
use crate::mesh::{builtin_mesh, load_obj, Mesh};
use crate::pose::pose_rows;
use crate::scene::{Scene, SceneObject};
use crate::sensor::Sensor;
use crate::shadow::{ShadowMode, ShadowSettings};
use crate::verify::{Hypothesis, HypothesisFile, Record, SensedImage, Verifier, VerifySettings, MAX_CHUNK};
use glam::{DMat4, DVec3};
use hypotheses::{propose, Candidate};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::Serialize;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// The paper's triangulation angle.
pub const THETA_DEG: f64 = 45.0;

/// How big an experiment is.
#[derive(Debug, Clone, Copy)]
pub struct ExperimentConfig {
    /// How many of the models, in `model_order`'s order (2 to 14).
    pub models: usize,
    pub views_per_model: usize,
    /// Image side, pixels (the image spans 5 model units).
    pub size: u32,
    pub seed: u64,
}

impl ExperimentConfig {
    /// Every model in five views at 256², as the paper's five images per object.
    pub fn full(seed: u64) -> Self {
        Self { models: 14, views_per_model: 5, size: 256, seed }
    }

    /// Seven models in one view each at 160².
    pub fn quick(seed: u64) -> Self {
        Self { models: 7, views_per_model: 1, size: 160, seed }
    }
}

/// What a run produced.
pub struct ExperimentOutput {
    pub scored: Vec<Scored>,
    pub summary: Summary,
    pub views: usize,
}

/// One model of the experiment.
struct Model {
    name: String,
    /// As a hypothesis file in `views/<view>/` names it.
    reference: String,
    mesh: Arc<Mesh>,
}

/// The files and directories of an experiment's set.
const SET_FILES: [&str; 3] = ["table.md", "summary.json", "scores.png"];
const SET_DIRS: [&str; 2] = ["models", "views"];

/// Built-ins and generated parts interleaved, so a smaller experiment still mixes both; the
/// generated ones written into `models_dir`.
fn model_order(models_dir: &Path, ledger: &Ledger) -> Result<Vec<Model>> {
    std::fs::create_dir_all(models_dir).map_err(|e| Error::io(models_dir, e))?;
    let mut generated = Vec::new();
    for (name, mesh) in generated_parts()? {
        let path = models_dir.join(format!("{name}.obj"));
        write_obj(&path, &mesh)?;
        // Rendered and verified as `verify` will read it.
        let mesh = Arc::new(load_obj(&path, ledger)?);
        generated.push(Model { reference: format!("../../models/{name}.obj"), name, mesh });
    }
    let builtins: Vec<Model> = BUILTIN_PARTS
        .iter()
        .map(|&reference| {
            let name = reference.trim_start_matches("builtin:").split(':').next().unwrap_or(reference).to_string();
            Ok(Model { name, reference: reference.to_string(), mesh: Arc::new(builtin_mesh(reference)?) })
        })
        .collect::<Result<_>>()?;
    let mut order = Vec::new();
    let mut generated = generated.into_iter();
    for builtin in builtins {
        order.push(builtin);
        order.extend(generated.next());
    }
    order.extend(generated);
    Ok(order)
}

/// The sensed image's sensor effects: axial noise, grazing losses beyond 80°, mixed pixels at
/// depth jumps over 0.05 units, and a working volume that starts 0.01 units above the table, so
/// the table is not measured (the scores' N_i counts every valid sensed pixel: with the table
/// in it, s5 would reject every hypothesis of a part); the noise seeded per view.
fn sensed_effects(view: u32) -> Effects {
    Effects {
        range: Some(WorkingVolume { min_z: Some(0.01), max_z: None }),
        noise: Some(Noise {
            sigma: 0.004,
            seed: view,
            depth_coefficient: 0.0,
            depth_reference: 0.0,
            incidence_coefficient: 0.0,
        }),
        grazing: Some(Grazing { max_incidence_deg: 80.0 }),
        edges: Some(Edges { jump: 0.05, width_px: 1 }),
        ..Effects::default()
    }
}

/// `hypotheses.json` as written: what `rangesynth verify` reads.
#[derive(Serialize)]
struct HypothesisFileOut<'a> {
    tolerance: f64,
    shadow: ShadowSettings,
    effects: Effects,
    hypotheses: Vec<HypothesisOut<'a>>,
}

#[derive(Serialize)]
struct HypothesisOut<'a> {
    id: &'a str,
    model: &'a str,
    pose: [[f64; 4]; 4],
    bindings: &'a [(u32, u32)],
}

/// Runs the experiment into `out`, replacing what an earlier run left there; `progress` is
/// told how many views are done.
pub fn run_experiment(
    verifier: &Verifier,
    config: &ExperimentConfig,
    out: &Path,
    progress: &mut dyn FnMut(usize, usize),
) -> Result<ExperimentOutput> {
    let set = StagedSet::new(out, &SET_FILES, &SET_DIRS)?;
    let mut models = model_order(&set.staged("models"), verifier.renderer().ledger())?;
    if !(2..=models.len()).contains(&config.models) || config.views_per_model == 0 {
        return Err(Error::Scene(format!(
            "an experiment needs 2 to {} models and at least one view of each",
            models.len()
        )));
    }
    models.truncate(config.models);
    let candidates: Vec<Candidate> =
        models.iter().map(|m| Candidate { reference: &m.reference, mesh: &m.mesh }).collect();
    let table = Arc::new(builtin_mesh("builtin:plane:6")?);
    // `size`² pixels over 5 model units, centred on the table.
    let sensor = Sensor::square(config.size, 5.0, THETA_DEG);
    let total = models.len() * config.views_per_model;
    let mut scored = Vec::new();
    for (index, (truth, view)) in
        (0..models.len()).flat_map(|m| (0..config.views_per_model).map(move |v| (m, v))).enumerate()
    {
        let model = &models[truth];
        let name = format!("{}-{}", model.name, view + 1);
        let dir = set.staged("views").join(&name);
        std::fs::create_dir_all(&dir).map_err(|e| Error::io(&dir, e))?;
        let mut rng = ChaCha8Rng::seed_from_u64(config.seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) ^ index as u64);
        // A random turn about z, the bounding sphere's centre moved near the image's centre.
        let (centre, _) = model.mesh.bounding_sphere();
        let turn = DMat4::from_rotation_z(rng.gen_range(0.0..std::f64::consts::TAU));
        let target = DVec3::new(rng.gen_range(-0.3..0.3), rng.gen_range(-0.3..0.3), 0.0);
        let turned_centre = turn.transform_point3(centre);
        let pose = DMat4::from_translation(target - DVec3::new(turned_centre.x, turned_centre.y, 0.0)) * turn;
        let scene = Scene {
            sensor: sensor.clone(),
            shadow: ShadowSettings::of(ShadowMode::Depth),
            effects: sensed_effects(index as u32 + 1),
            objects: [
                (model.reference.clone(), model.mesh.clone(), pose),
                ("builtin:plane:6".into(), table.clone(), DMat4::IDENTITY),
            ]
            .into_iter()
            .map(|(model_ref, mesh, pose)| SceneObject { model_ref, mesh, pose, reflectivity: None })
            .collect(),
        };
        let rendered = verifier.renderer().render(&scene)?;
        let range_path = dir.join("range.exr");
        write_range_image(&range_path, &RangeImage { effects: None, ..RangeImage::from(&rendered) })?;

        // What a view reads back, it holds only for the view, on top of what the run holds.
        let view_ledger = Ledger::new(MemoryBudget::new(verifier.renderer().ledger().available()));
        let image = read_range_image(&range_path, &view_ledger)?;
        let header_sensor = image.sensor.clone().ok_or_else(|| Error::file(&range_path, "has no sensor header"))?;
        let sensed = SensedImage::new(&image, &header_sensor)?;
        let surfaces = model.mesh.surface_count();
        let mut visible: Vec<(u32, u64)> = sensed
            .segments
            .iter()
            .zip(&sensed.segment_population)
            .filter(|(&label, _)| label <= surfaces)
            .map(|(&label, &n)| (label, n))
            .collect();
        visible.sort_by_key(|&(label, n)| (std::cmp::Reverse(n), label));
        let visible: Vec<u32> = visible.into_iter().map(|(label, _)| label).collect();
        let proposals = propose(&mut rng, &candidates, truth, (pose, pose.transform_point3(centre)), &visible);

        let hypotheses_path = dir.join("hypotheses.json");
        let file = HypothesisFileOut {
            tolerance: crate::verify::DEFAULT_TOLERANCE,
            shadow: ShadowSettings::of(ShadowMode::Label),
            effects: Effects::default(),
            hypotheses: proposals
                .iter()
                .map(|p| HypothesisOut { id: &p.id, model: &p.model, pose: pose_rows(&p.pose), bindings: &p.bindings })
                .collect(),
        };
        let json = serde_json::to_string_pretty(&file).map_err(|e| Error::file(&hypotheses_path, e))?;
        write_atomically(&hypotheses_path, |f| {
            f.write_all(json.as_bytes()).map_err(|e| Error::io(&hypotheses_path, e))
        })?;

        // As `rangesynth verify hypotheses.json --scene range.exr --compare-shadow` does it.
        let file = HypothesisFile::from_file(&hypotheses_path, &view_ledger)?;
        let hypotheses: Vec<Hypothesis> = file
            .hypotheses
            .into_iter()
            .map(|h| {
                Ok(Hypothesis { model: verifier.model(&h.model, &dir)?, id: h.id, pose: h.pose, bindings: h.bindings })
            })
            .collect::<Result<_>>()?;
        let settings = VerifySettings {
            sensor: file.sensor.unwrap_or(header_sensor),
            shadow: file.shadow.or(image.shadow).unwrap_or_default(),
            effects: file.effects.or(image.effects).unwrap_or_default(),
            tolerance: file.tolerance,
            compare_shadow: true,
            chunk_size: MAX_CHUNK,
        };
        let results = verifier.verify(&sensed, &settings, &hypotheses, &mut |_| {})?;
        let mut lines = Vec::new();
        for v in &results {
            serde_json::to_writer(&mut lines, &Record::new(v, &sensed)).map_err(|e| Error::file(&dir, e))?;
            lines.push(b'\n');
            let plain = v.unshadowed.as_ref().map_or(v.scores.s, |(_, u)| u.s);
            scored.push(Scored {
                view: name.clone(),
                model: model.name.clone(),
                correct: v.id.starts_with(CORRECT),
                plain,
                shadow: v.scores.s,
            });
        }
        let scores_path = dir.join("scores.jsonl");
        write_atomically(&scores_path, |f| f.write_all(&lines).map_err(|e| Error::io(&scores_path, e)))?;
        progress(index + 1, total);
    }

    let summary = summarise(&scored);
    let text = table_markdown(&scored);
    let [table_path, summary_path, plot_path] = SET_FILES.map(|name| set.staged(name));
    let outputs: [(PathBuf, Vec<u8>); 2] = [
        (table_path, text.into_bytes()),
        (summary_path.clone(), serde_json::to_vec_pretty(&summary).map_err(|e| Error::file(summary_path, e))?),
    ];
    for (path, bytes) in &outputs {
        write_atomically(path, |f| f.write_all(bytes).map_err(|e| Error::io(path, e)))?;
    }
    write_plot(&plot_path, &scored)?;
    set.commit()?;
    Ok(ExperimentOutput { scored, summary, views: total })
}
