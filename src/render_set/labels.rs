//! `labels.json`: which object and surface each label of a render stands for. The file is
//! streamed, one entry at a time, to its temporary file: a scene of 100,000 objects would
//! otherwise hold its whole text in memory.

use crate::error::{Error, Result};
use crate::io::write_atomically;
use crate::scene::Scene;
use serde::{Deserialize, Serialize, Serializer};
use std::io::{BufWriter, Write};
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

/// The entries of `scene`, whose objects' first labels less one are `bases`.
fn entries<'a>(scene: &'a Scene, bases: &'a [u32]) -> impl Iterator<Item = LabelEntry> + 'a {
    scene.objects.iter().zip(bases).enumerate().flat_map(|(object, (o, &base))| {
        o.mesh.surface_names.iter().enumerate().map(move |(i, name)| LabelEntry {
            label: base + i as u32 + 1,
            object,
            model: o.model_ref.clone(),
            surface: i as u32 + 1,
            surface_name: name.clone(),
        })
    })
}

pub fn label_map(scene: &Scene) -> Result<Vec<LabelEntry>> {
    let bases = scene.label_bases()?;
    Ok(entries(scene, &bases).collect())
}

/// `{"labels": [...]}`, the list serialised as it is made.
#[derive(Serialize)]
struct LabelFile<'a> {
    labels: Entries<'a>,
}

struct Entries<'a> {
    scene: &'a Scene,
    bases: &'a [u32],
}

impl Serialize for Entries<'_> {
    fn serialize<S: Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        serializer.collect_seq(entries(self.scene, self.bases))
    }
}

/// Writes `labels.json`: the label map as pretty-printed JSON and a newline.
pub fn write_label_map(path: &Path, scene: &Scene) -> Result<()> {
    let bases = scene.label_bases()?;
    let file = LabelFile { labels: Entries { scene, bases: &bases } };
    write_atomically(path, |out| {
        let mut out = BufWriter::new(out);
        serde_json::to_writer_pretty(&mut out, &file).map_err(|e| Error::io(path, e.into()))?;
        out.write_all(b"\n").and_then(|()| out.flush()).map_err(|e| Error::io(path, e))
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::builtin_mesh;
    use crate::scene::SceneObject;
    use std::sync::Arc;

    /// The text as it was made before the file was streamed: the whole map at once.
    fn whole_text(scene: &Scene) -> String {
        #[derive(Serialize)]
        struct File {
            labels: Vec<LabelEntry>,
        }
        serde_json::to_string_pretty(&File { labels: label_map(scene).unwrap() }).unwrap() + "\n"
    }

    #[test]
    fn the_streamed_file_is_the_whole_text_byte_for_byte() {
        let dir = crate::io::scratch_dir("labels-stream");
        let path = dir.join("labels.json");
        let mut scene = Scene::from_toml(
            "[sensor]\nkind = \"orthographic\"\nwidth = 4\nheight = 4\npitch = [0.1, 0.1]\norigin = [0.0, 0.0]\n\
             theta_deg = 30.0\n",
            Path::new("."),
            &crate::limits::Ledger::default(),
        )
        .unwrap();
        // No objects: an empty list, `[]`, as before.
        write_label_map(&path, &scene).unwrap();
        assert_eq!(std::fs::read_to_string(&path).unwrap(), whole_text(&scene));
        for model in ["builtin:box", "builtin:plane:6", "builtin:cylinder:8"] {
            let mesh = Arc::new(builtin_mesh(model).unwrap());
            let (model_ref, pose) = (model.to_string(), glam::DMat4::IDENTITY);
            scene.objects.push(SceneObject { model_ref, mesh, pose, reflectivity: None });
        }
        write_label_map(&path, &scene).unwrap();
        let text = std::fs::read_to_string(&path).unwrap();
        assert_eq!(text, whole_text(&scene));
        assert!(text.contains("\"surface_name\""), "{text}");
    }
}
