//! A BOP dataset directory as `rangesynth bop` reads it (the layout the BOP toolkit's
//! dataset-format page documents):
//!
//! - `models/models_info.json`: per object id, its `diameter` (mm), and `models/obj_NNNNNN.ply`;
//! - `SPLIT/SSSSSS/scene_camera.json`: per image id, `cam_K` (3×3, row-major) and `depth_scale`
//!   (depth in mm = PNG value × depth_scale);
//! - `SPLIT/SSSSSS/scene_gt.json` (optional): per image id, the objects' `cam_R_m2c`,
//!   `cam_t_m2c` (mm) and `obj_id`;
//! - `SPLIT/SSSSSS/depth/IIIIII.png`: 16-bit depth images.
//!
//! Every file is read as any input is (a regular file, within the run's budget), and every
//! problem is an error naming the file, the scene and image and the field.

use super::results::pose_from_bop;
use crate::error::{Error, Result};
use crate::io::{parse_json, read_input_text};
use crate::limits::Ledger;
use crate::sensor::Intrinsics;
use crate::untrusted::quoted;
use glam::DMat4;
use serde::Deserialize;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// One image's camera: its intrinsics (the image's size comes from its depth image) and the
/// depth scale.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Camera {
    pub fx: f64,
    pub fy: f64,
    pub cx: f64,
    pub cy: f64,
    /// Millimetres per unit of the depth PNG.
    pub depth_scale: f64,
}

impl Camera {
    pub fn intrinsics(&self, (width, height): (u32, u32)) -> Intrinsics {
        Intrinsics { width, height, fx: self.fx, fy: self.fy, cx: self.cx, cy: self.cy }
    }
}

/// One object's ground-truth pose in an image (camera-from-model, mm).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GtPose {
    pub obj_id: u32,
    pub pose: DMat4,
}

/// What a scene's files say, per image id.
#[derive(Debug, Default)]
pub struct SceneFiles {
    pub cameras: BTreeMap<u32, Camera>,
    /// Empty where the scene has no `scene_gt.json`.
    pub gt: BTreeMap<u32, Vec<GtPose>>,
}

/// A dataset's root and split, and its objects' diameters.
pub struct Dataset {
    root: PathBuf,
    split: String,
    diameters: BTreeMap<u32, f64>,
}

#[derive(Deserialize)]
struct ModelInfo {
    diameter: f64,
}

#[derive(Deserialize)]
struct CameraEntry {
    #[serde(rename = "cam_K")]
    cam_k: Vec<f64>,
    depth_scale: f64,
}

#[derive(Deserialize)]
struct GtEntry {
    #[serde(rename = "cam_R_m2c")]
    cam_r_m2c: Vec<f64>,
    cam_t_m2c: Vec<f64>,
    obj_id: u32,
}

/// A dataset's JSON file as `T`; a parse error names the file.
fn read_json<T: serde::de::DeserializeOwned>(path: &Path, what: &str, ledger: &Ledger) -> Result<T> {
    let text = read_input_text(path, what, ledger)?;
    parse_json(&text).map_err(|e| Error::file(path, e.to_string()))
}

/// A JSON object's entries as the file gives them, every key kept: serde_json's maps keep a
/// repeated key's last value and say nothing, where a dataset that gives an image two cameras
/// is malformed.
struct Entries<V>(Vec<(String, V)>);

impl<'de, V: serde::Deserialize<'de>> serde::Deserialize<'de> for Entries<V> {
    fn deserialize<D: serde::Deserializer<'de>>(deserializer: D) -> std::result::Result<Self, D::Error> {
        struct Visitor<V>(std::marker::PhantomData<V>);
        impl<'de, V: serde::Deserialize<'de>> serde::de::Visitor<'de> for Visitor<V> {
            type Value = Entries<V>;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("an object keyed by ids")
            }
            fn visit_map<A: serde::de::MapAccess<'de>>(self, mut map: A) -> std::result::Result<Self::Value, A::Error> {
                let mut entries = Vec::new();
                while let Some(entry) = map.next_entry()? {
                    entries.push(entry);
                }
                Ok(Entries(entries))
            }
        }
        deserializer.deserialize_map(Visitor(std::marker::PhantomData))
    }
}

impl<V> Entries<V> {
    /// The entries by id (their keys written as whole numbers, "1" or "000001"), each id once.
    fn by_id(self, path: &Path, what: &str) -> Result<Vec<(u32, V)>> {
        let mut seen = std::collections::BTreeSet::new();
        self.0
            .into_iter()
            .map(|(key, value)| {
                let id: u32 = key
                    .parse()
                    .map_err(|_| Error::file(path, format!("{what} id {} is not a whole number", quoted(&key))))?;
                match seen.insert(id) {
                    true => Ok((id, value)),
                    false => Err(Error::file(path, format!("{what} {id} is given twice (key {})", quoted(&key)))),
                }
            })
            .collect()
    }
}

impl Dataset {
    /// Opens the dataset at `root`, split `split`, reading its models' diameters.
    pub fn open(root: &Path, split: &str, ledger: &Ledger) -> Result<Self> {
        if split.is_empty() || split.contains(['/', '\\']) || split == ".." {
            return Err(Error::Scene(format!("--split {split:?} must name one directory of the dataset")));
        }
        let info_path = root.join("models").join("models_info.json");
        let entries: Entries<ModelInfo> = read_json(&info_path, "models_info.json", ledger)?;
        let mut diameters = BTreeMap::new();
        for (id, info) in entries.by_id(&info_path, "object")? {
            if !(info.diameter.is_finite() && info.diameter > 0.0) {
                return Err(Error::file(
                    &info_path,
                    format!("object {id}: diameter = {} must be positive and finite", info.diameter),
                ));
            }
            diameters.insert(id, info.diameter);
        }
        Ok(Self { root: root.to_path_buf(), split: split.to_string(), diameters })
    }

    /// An object's diameter (mm); an id that models_info.json does not list is refused.
    pub fn diameter(&self, obj_id: u32) -> Result<f64> {
        self.diameters.get(&obj_id).copied().ok_or_else(|| {
            let listed: Vec<String> = self.diameters.keys().take(20).map(u32::to_string).collect();
            Error::file(
                self.root.join("models").join("models_info.json"),
                format!("lists no object {obj_id} (it lists {})", listed.join(", ")),
            )
        })
    }

    /// The model of an object listed in models_info.json.
    pub fn model_path(&self, obj_id: u32) -> Result<PathBuf> {
        self.diameter(obj_id)?;
        Ok(self.root.join("models").join(format!("obj_{obj_id:06}.ply")))
    }

    fn scene_dir(&self, scene_id: u32) -> PathBuf {
        self.root.join(&self.split).join(format!("{scene_id:06}"))
    }

    /// The depth image of an image.
    pub fn depth_path(&self, scene_id: u32, im_id: u32) -> PathBuf {
        self.scene_dir(scene_id).join("depth").join(format!("{im_id:06}.png"))
    }

    /// A scene's cameras and ground truth.
    pub fn scene(&self, scene_id: u32, ledger: &Ledger) -> Result<SceneFiles> {
        let dir = self.scene_dir(scene_id);
        let camera_path = dir.join("scene_camera.json");
        let entries: Entries<CameraEntry> = read_json(&camera_path, "scene_camera.json", ledger)?;
        let mut files = SceneFiles::default();
        for (im_id, entry) in entries.by_id(&camera_path, "image")? {
            let at = |field: &str, reason: String| {
                Error::file(&camera_path, format!("scene {scene_id}, image {im_id}: {field} {reason}"))
            };
            let k = &entry.cam_k;
            if k.len() != 9 || k.iter().any(|v| !v.is_finite()) {
                return Err(at(
                    "cam_K",
                    format!("must be 9 finite numbers (a 3×3 matrix, row-major); it has {}", k.len()),
                ));
            }
            if [k[1], k[3], k[6], k[7]] != [0.0; 4] || k[8] != 1.0 {
                return Err(at(
                    "cam_K",
                    format!("{k:?} is not [fx, 0, cx, 0, fy, cy, 0, 0, 1] (skew is not modelled)"),
                ));
            }
            if !(k[0] > 0.0 && k[4] > 0.0) {
                return Err(at(
                    "cam_K",
                    format!("has focal lengths fx = {}, fy = {}; both must be positive", k[0], k[4]),
                ));
            }
            if !(entry.depth_scale.is_finite() && entry.depth_scale > 0.0) {
                return Err(at("depth_scale", format!("= {} must be positive and finite", entry.depth_scale)));
            }
            let camera = Camera { fx: k[0], fy: k[4], cx: k[2], cy: k[5], depth_scale: entry.depth_scale };
            files.cameras.insert(im_id, camera);
        }
        let gt_path = dir.join("scene_gt.json");
        if gt_path.exists() {
            let entries: Entries<Vec<GtEntry>> = read_json(&gt_path, "scene_gt.json", ledger)?;
            for (im_id, objects) in entries.by_id(&gt_path, "image")? {
                let poses = objects
                    .iter()
                    .enumerate()
                    .map(|(k, o)| {
                        let pose = pose_from_bop(&o.cam_r_m2c, &o.cam_t_m2c).map_err(|reason| {
                            Error::file(
                                &gt_path,
                                format!("scene {scene_id}, image {im_id}, ground truth {k}: {reason}"),
                            )
                        })?;
                        Ok(GtPose { obj_id: o.obj_id, pose })
                    })
                    .collect::<Result<_>>()?;
                files.gt.insert(im_id, poses);
            }
        }
        Ok(files)
    }

    /// A scene's camera of an image, or an error naming the file, scene and image.
    pub fn camera(&self, files: &SceneFiles, scene_id: u32, im_id: u32) -> Result<Camera> {
        files.cameras.get(&im_id).copied().ok_or_else(|| {
            Error::file(
                self.scene_dir(scene_id).join("scene_camera.json"),
                format!("has no image {im_id} (scene {scene_id})"),
            )
        })
    }
}
