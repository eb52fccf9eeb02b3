//! `labels.json`: which object and surface each label of a render stands for.

use super::write_atomically;
use crate::error::{Error, Result};
use crate::scene::Scene;
use serde::{Deserialize, Serialize};
use std::io::Write;
use std::path::Path;

#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct LabelEntry {
    pub label: u32,
    /// Index of the object in the scene file, from 0.
    pub object: usize,
    pub model: String,
    /// The surface's id within its model, from 1.
    pub surface: u32,
    pub surface_name: String,
}

pub fn label_map(scene: &Scene) -> Result<Vec<LabelEntry>> {
    let bases = scene.label_bases()?;
    Ok(scene
        .objects
        .iter()
        .zip(bases)
        .enumerate()
        .flat_map(|(object, (o, base))| {
            o.mesh.surface_names.iter().enumerate().map(move |(i, name)| LabelEntry {
                label: base + i as u32 + 1,
                object,
                model: o.model_ref.clone(),
                surface: i as u32 + 1,
                surface_name: name.clone(),
            })
        })
        .collect())
}

pub fn write_label_map(path: &Path, scene: &Scene) -> Result<()> {
    #[derive(Serialize)]
    struct File {
        labels: Vec<LabelEntry>,
    }
    let text = serde_json::to_string_pretty(&File { labels: label_map(scene)? }).map_err(|e| Error::file(path, e))?;
    write_atomically(path, |file| file.write_all((text + "\n").as_bytes()).map_err(|e| Error::io(path, e)))
}
