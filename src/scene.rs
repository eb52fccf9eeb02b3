//! Scenes: a sensor, a shadow setting, the sensor effects (src/effects.rs) and posed models,
//! read from the TOML of DESIGN.md "Interfaces". Labels are numbered across objects in file order: object k's surface s has
//! label `label_base(k) + s`.

use crate::effects::Effects;
use crate::error::{Error, Result};
use crate::io::read_input_text;
use crate::limits::MemoryBudget;
use crate::mesh::{builtin_mesh, canonical_builtin_name, load_obj, Mesh};
use crate::pose::pose_from_rows;
use crate::sensor::Sensor;
use crate::shadow::ShadowSettings;
use glam::DMat4;
use serde::Deserialize;
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;

#[derive(Debug, Clone)]
pub struct Scene {
    pub sensor: Sensor,
    pub shadow: ShadowSettings,
    pub effects: Effects,
    pub objects: Vec<SceneObject>,
}

#[derive(Debug, Clone)]
pub struct SceneObject {
    /// The model reference as the scene gave it (a path or a `builtin:` name).
    pub model_ref: String,
    pub mesh: Arc<Mesh>,
    /// Model → range frame, rigid.
    pub pose: DMat4,
    /// The reflectivity of all its surfaces, in [0, 1], where the scene sets it
    /// (`[effects.reflectivity]`); else each surface's own.
    pub reflectivity: Option<f64>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct SceneFile {
    sensor: Sensor,
    #[serde(default)]
    shadow: ShadowSettings,
    #[serde(default)]
    effects: Effects,
    #[serde(default)]
    object: Vec<ObjectEntry>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct ObjectEntry {
    model: String,
    #[serde(default = "identity_rows", deserialize_with = "crate::exact_array::matrix")]
    pose: [[f64; 4]; 4],
    reflectivity: Option<f64>,
}

fn identity_rows() -> [[f64; 4]; 4] {
    DMat4::IDENTITY.to_cols_array_2d()
}

/// Bytes of memory parsing takes per byte of TOML text, at most (toml's document tree).
const TOML_EXPANSION: u64 = 16;

impl Scene {
    /// Reads a scene file; files it names (and it) are loaded within `budget`.
    pub fn from_file(path: &Path, budget: MemoryBudget) -> Result<Self> {
        let text = read_input_text(path, "scene file", budget, TOML_EXPANSION)?;
        Self::from_toml(&text, path.parent().unwrap_or(Path::new(".")), budget).map_err(|e| match e {
            Error::Scene(reason) => Error::file(path, reason),
            other => other,
        })
    }

    /// Parses a scene; model paths are relative to `base_dir`, and model files are loaded
    /// within `budget`. Each model is loaded once, however many objects name it.
    pub fn from_toml(text: &str, base_dir: &Path, budget: MemoryBudget) -> Result<Self> {
        let file: SceneFile = toml::from_str(text).map_err(|e| Error::Scene(e.to_string()))?;
        file.sensor.validate()?;
        file.effects.validate()?;
        let mut loaded: HashMap<String, Arc<Mesh>> = HashMap::new();
        let mut objects = Vec::with_capacity(file.object.len());
        for entry in file.object {
            let key = model_key(&entry.model, base_dir)?;
            let mesh = match loaded.get(&key) {
                Some(mesh) => mesh.clone(),
                None => {
                    let mesh = Arc::new(load_model(&entry.model, base_dir, budget)?);
                    loaded.insert(key, mesh.clone());
                    mesh
                }
            };
            if let Some(r) = entry.reflectivity.filter(|r| !(0.0..=1.0).contains(r)) {
                return Err(Error::Scene(format!(
                    "object {} ({}): reflectivity = {r} is out of range: it must be in [0, 1]",
                    objects.len() + 1,
                    entry.model
                )));
            }
            let pose = pose_from_rows(entry.pose, &format!("object {} ({})", objects.len() + 1, entry.model))?;
            objects.push(SceneObject { model_ref: entry.model, mesh, pose, reflectivity: entry.reflectivity });
        }
        let scene = Scene { sensor: file.sensor, shadow: file.shadow, effects: file.effects, objects };
        scene.label_bases()?;
        Ok(scene)
    }

    /// The label of object k's surface s is `label_bases()[k] + s`. Fails when the labels
    /// would not fit in u32.
    pub fn label_bases(&self) -> Result<Vec<u32>> {
        let mut next: u64 = 0;
        self.objects
            .iter()
            .map(|o| {
                let base = next;
                next += u64::from(o.mesh.surface_count());
                u32::try_from(next)
                    .map(|_| base as u32)
                    .map_err(|_| Error::Scene("the scene has more than 2^32 - 1 surfaces".into()))
            })
            .collect()
    }
}

impl Scene {
    /// The reflectivity of each label, label 0 (no surface) included: an object's own
    /// `reflectivity`, else its surface's material, else `default`.
    pub fn reflectivity_table(&self, default: f64) -> Vec<f32> {
        let mut table = vec![0.0];
        for object in &self.objects {
            let surfaces = object.mesh.surface_reflectivities(default);
            table.extend(surfaces.map(|r| object.reflectivity.unwrap_or(r) as f32));
        }
        table
    }
}

/// Loads `builtin:…` by name, anything else as an OBJ path relative to `base_dir`, within
/// `budget`.
pub fn load_model(reference: &str, base_dir: &Path, budget: MemoryBudget) -> Result<Mesh> {
    if reference.starts_with("builtin:") {
        builtin_mesh(reference)
    } else {
        let path: PathBuf = base_dir.join(reference);
        load_obj(&path, budget)
    }
}

/// One key per model, for caches: a built-in's canonical name (so `builtin:sphere:032` and
/// `builtin:sphere:32` are one model), or the file's path.
pub fn model_key(reference: &str, base_dir: &Path) -> Result<String> {
    if reference.starts_with("builtin:") {
        canonical_builtin_name(reference)
    } else {
        Ok(base_dir.join(reference).display().to_string())
    }
}
