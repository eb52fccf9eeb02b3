//! Scenes: a sensor, a shadow setting, the sensor effects (src/effects.rs) and posed models,
//! read from the TOML of docs/design.md "Interfaces". Labels are numbered across objects in file order: object k's surface s has
//! label `label_base(k) + s`.

use crate::effects::Effects;
use crate::error::{Error, Result};
use crate::io::{parse_toml, read_input_text};
use crate::limits::{FileId, Ledger};
use crate::mesh::{
    builtin_bytes, builtin_mesh, canonical_builtin_name, load_model_file, Mesh, SurfaceChoice, SurfaceRule,
};
use crate::pose::pose_from_rows;
use crate::sensor::Sensor;
use crate::shadow::ShadowSettings;
use crate::untrusted::quoted;
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
    /// Model units to scene units, applied in the model's frame before the pose.
    #[serde(default = "crate::mesh::default_model_scale")]
    scale: f64,
    /// How the model's triangles are grouped into surfaces (`SurfaceChoice`).
    surfaces: Option<SurfaceRule>,
    crease_deg: Option<f64>,
}

fn identity_rows() -> [[f64; 4]; 4] {
    DMat4::IDENTITY.to_cols_array_2d()
}

/// Bytes of memory parsing takes per byte of TOML text, at most: toml's document tree, whose
/// worst case is an array of one-digit numbers (measured: tests/memory.rs).
const TOML_EXPANSION: u64 = 200;

impl Scene {
    /// Reads a scene file; it and the files it names are charged to `ledger`.
    pub fn from_file(path: &Path, ledger: &Ledger) -> Result<Self> {
        let text = read_input_text(path, "scene file", ledger)?;
        Self::from_toml(&text, path.parent().unwrap_or(Path::new(".")), ledger).map_err(|e| match e {
            Error::Scene(reason) => Error::file(path, reason),
            other => other,
        })
    }

    /// Parses a scene; model paths are relative to `base_dir`. Model files, the objects and
    /// their labels are charged to `ledger`. Each model file is loaded once, however many
    /// objects name it and however they spell its path.
    pub fn from_toml(text: &str, base_dir: &Path, ledger: &Ledger) -> Result<Self> {
        ledger.charge("parsing the scene's TOML", text.len() as u64 * TOML_EXPANSION)?;
        let file: SceneFile = parse_toml(text)?;
        file.sensor.validate()?;
        file.effects.validate()?;
        // Each model at each scale and surfaces, once.
        let mut loaded: HashMap<ModelFormKey, Arc<Mesh>> = HashMap::new();
        let mut objects = Vec::with_capacity(file.object.len());
        let mut labels: u64 = 0;
        for entry in file.object {
            let object = objects.len() + 1;
            let owner = format!("object {object} ({})", quoted(&entry.model));
            let surfaces = SurfaceChoice::from_keys(entry.surfaces, entry.crease_deg, &owner)?;
            let key = model_form_key(&entry.model, base_dir, surfaces, entry.scale)?;
            let mesh = match loaded.get(&key) {
                Some(mesh) => mesh.clone(),
                None => {
                    let mesh = Arc::new(load_model_as(&entry.model, base_dir, ledger, surfaces, entry.scale)?);
                    loaded.insert(key, mesh.clone());
                    mesh
                }
            };
            // What an object and its labels take until the run ends: its entry here, and its
            // labels' entries in the tables of a render and in labels.json's summary.
            labels += u64::from(mesh.surface_count());
            ledger.charge(
                format_args!("object {object} ({}, {labels} labels so far)", quoted(&entry.model)),
                BYTES_PER_OBJECT + u64::from(mesh.surface_count()) * BYTES_PER_LABEL,
            )?;
            if let Some(r) = entry.reflectivity.filter(|r| !(0.0..=1.0).contains(r)) {
                return Err(Error::Scene(format!(
                    "object {object} ({}): reflectivity = {r} is out of range: it must be in [0, 1]",
                    quoted(&entry.model)
                )));
            }
            let pose = pose_from_rows(entry.pose, &owner)?;
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

/// Loads `builtin:…` by name, anything else as a model file (OBJ, PLY or STL, by its
/// extension: `load_model_file`) relative to `base_dir`, charged to `ledger`.
pub fn load_model(reference: &str, base_dir: &Path, ledger: &Ledger) -> Result<Mesh> {
    if reference.starts_with("builtin:") {
        ledger.charge(format_args!("building {}", quoted(reference)), builtin_bytes(reference)?)?;
        builtin_mesh(reference)
    } else {
        let path: PathBuf = base_dir.join(reference);
        load_model_file(&path, ledger)
    }
}

/// [`load_model`], its surfaces as `surfaces` asks ([`Mesh::with_surfaces`]) and scaled by
/// `scale` ([`Mesh::scaled`]): a model as an object or a hypothesis names it.
pub fn load_model_as(
    reference: &str,
    base_dir: &Path,
    ledger: &Ledger,
    surfaces: SurfaceChoice,
    scale: f64,
) -> Result<Mesh> {
    load_model(reference, base_dir, ledger)?.with_surfaces(surfaces)?.scaled(scale, ledger)
}

/// What tells apart the meshes [`load_model_as`] makes, for caches: the model, its surfaces and
/// its scale.
pub type ModelFormKey = (ModelKey, (Option<SurfaceRule>, u64), u64);

/// The key of the mesh [`load_model_as`] makes of these.
pub fn model_form_key(reference: &str, base_dir: &Path, surfaces: SurfaceChoice, scale: f64) -> Result<ModelFormKey> {
    Ok((model_key(reference, base_dir)?, surfaces.key(), scale.to_bits()))
}

/// Bytes an object of a scene holds (its entry, its pose, its draw), and each of its labels
/// (a render's tables of a word or two a label, and a line of the printed summary's).
const BYTES_PER_OBJECT: u64 = 512;
const BYTES_PER_LABEL: u64 = 64;

/// One key per model, for caches: a built-in's canonical name (so `builtin:sphere:032` and
/// `builtin:sphere:32` are one model), or the file's identity (so `m.obj`, `./m.obj` and a
/// link to it are one model) with its length and modification time, so that a file rewritten
/// in place is read anew by a long-lived cache (a `Verifier`'s), not served as it was.
#[derive(Debug, Clone, PartialEq, Eq, Hash)]
pub enum ModelKey {
    Builtin(String),
    File { id: FileId, length: u64, modified: Option<std::time::SystemTime> },
}

/// The key of the model `reference` names, relative to `base_dir`; a file that cannot be
/// found is an error naming it.
pub fn model_key(reference: &str, base_dir: &Path) -> Result<ModelKey> {
    if reference.starts_with("builtin:") {
        canonical_builtin_name(reference).map(ModelKey::Builtin)
    } else {
        let path = base_dir.join(reference);
        let file =
            |m: std::fs::Metadata| ModelKey::File { id: FileId::of(&m), length: m.len(), modified: m.modified().ok() };
        std::fs::metadata(&path).map(file).map_err(|e| Error::io(path, e))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::limits::MemoryBudget;

    const SENSOR: &str = "[sensor]\nkind = \"orthographic\"\nwidth = 8\nheight = 8\npitch = [0.1, 0.1]\n\
                          origin = [0.0, 0.0]\ntheta_deg = 30.0\n";

    fn two_boxes() -> String {
        format!("{SENSOR}[[object]]\nmodel = \"builtin:box\"\n[[object]]\nmodel = \"builtin:box\"\n")
    }

    /// What parsing two boxes charges before its second object: the text, the box built once,
    /// and the first object with its six labels.
    fn charged_before_the_second_box(text: &str) -> u64 {
        text.len() as u64 * TOML_EXPANSION
            + builtin_bytes("builtin:box").unwrap()
            + BYTES_PER_OBJECT
            + 6 * BYTES_PER_LABEL
    }

    #[test]
    fn a_scene_charges_its_text_each_model_once_and_each_object_with_its_labels() {
        let text = two_boxes();
        let ledger = Ledger::default();
        Scene::from_toml(&text, Path::new("."), &ledger).unwrap();
        assert_eq!(ledger.held(), charged_before_the_second_box(&text) + BYTES_PER_OBJECT + 6 * BYTES_PER_LABEL);
    }

    #[test]
    fn a_refused_object_is_named_with_its_number_and_the_labels_so_far() {
        let text = two_boxes();
        let budget = charged_before_the_second_box(&text) + BYTES_PER_OBJECT + 6 * BYTES_PER_LABEL - 1;
        let e = Scene::from_toml(&text, Path::new("."), &Ledger::new(MemoryBudget::new(budget))).unwrap_err();
        let message = e.to_string();
        assert!(message.contains("object 2 (\"builtin:box\", 12 labels so far)"), "{message}");
    }

    #[test]
    fn labels_are_numbered_across_objects_in_order_and_reflectivities_follow_them() {
        let text = format!(
            "{SENSOR}[[object]]\nmodel = \"builtin:box\"\nreflectivity = 0.25\n[[object]]\nmodel = \"builtin:step\"\n\
             [[object]]\nmodel = \"builtin:box\"\n"
        );
        let scene = Scene::from_toml(&text, Path::new("."), &Ledger::default()).unwrap();
        let step = builtin_mesh("builtin:step").unwrap().surface_count();
        assert_eq!(scene.label_bases().unwrap(), [0, 6, 6 + step]);
        // Label 0 (no surface), the first box's own reflectivity, then the default for the
        // built-ins, which have no materials.
        let mut expected = vec![0.0, 0.25, 0.25, 0.25, 0.25, 0.25, 0.25];
        expected.extend(vec![0.6; step as usize + 6]);
        assert_eq!(scene.reflectivity_table(0.6), expected);
    }
}
