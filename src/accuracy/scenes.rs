//! The scenes `rangesynth accuracy` measures every setting on: each built-in on a table, a
//! cluttered table, and a dense curved part (a sphere of about 100,000 triangles filling the
//! image), all at the paper's θ = 45°; plus any scene files the user names. Sensor effects are
//! left out: the sweep measures shadowing and rasterization, not the sensor's losses.

use super::settings::retessellated;
use crate::effects::Effects;
use crate::error::{Error, Result};
use crate::limits::Ledger;
use crate::mesh::builtin_mesh;
use crate::scene::{Scene, SceneObject};
use crate::sensor::Sensor;
use crate::shadow::ShadowSettings;
use glam::{DMat4, DVec3};
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// The tessellation curved built-ins are measured against: the shape itself, to within
/// 1/(2N²)·π² of its radius (a sagitta of 2.4·10⁻⁶ for the unit-diameter sphere at N = 1024,
/// the finest `builtin:sphere`; cylinders have at most 4096 sides).
pub const REFERENCE_TESSELLATION: u32 = 1024;

/// One scene of the sweep.
#[derive(Clone)]
pub struct SweepScene {
    pub name: String,
    pub scene: Scene,
    /// Where the scene's model paths are relative to.
    pub base_dir: PathBuf,
}

impl SweepScene {
    /// A scene file, named by its file name without extension; its effects are left out. Its
    /// first object is the part whose correct hypothesis is scored, so it needs one.
    pub fn from_file(path: &Path, ledger: &Ledger) -> Result<Self> {
        let scene = Scene { effects: Effects::default(), ..Scene::from_file(path, ledger)? };
        if scene.objects.is_empty() {
            return Err(Error::file(path, "the accuracy sweep scores the scene's first object, and it has none"));
        }
        let name = path.file_stem().map_or_else(|| path.display().to_string(), |s| s.to_string_lossy().into_owned());
        // A comma would split the scene's CSV field.
        let name = name.replace(',', ";");
        Ok(Self { name, scene, base_dir: path.parent().unwrap_or(Path::new(".")).to_path_buf() })
    }

    fn builtin(name: &str, scene: Scene) -> Self {
        Self { name: name.into(), scene, base_dir: PathBuf::from(".") }
    }
}

fn object(model: &str, pose: DMat4) -> Result<SceneObject> {
    Ok(SceneObject { model_ref: model.to_string(), mesh: Arc::new(builtin_mesh(model)?), pose, reflectivity: None })
}

/// The sweep's sensor: `size`² pixels over `extent` units, at the paper's θ = 45°.
fn sensor(size: u32, extent: f64) -> Sensor {
    Sensor::square(size, extent, 45.0)
}

/// The standard scenes on `size`² images; the first object of each is the part whose correct
/// hypothesis is scored.
pub fn standard_scenes(size: u32, dense_segments: u32) -> Result<Vec<SweepScene>> {
    let turned =
        |angle: f64, x: f64, y: f64| DMat4::from_translation(DVec3::new(x, y, 0.0)) * DMat4::from_rotation_z(angle);
    let table = || object("builtin:plane:6", DMat4::IDENTITY);
    let on_table = |name: &str, model: &str, pose: DMat4| -> Result<SweepScene> {
        Ok(SweepScene::builtin(
            name,
            Scene {
                sensor: sensor(size, 4.0),
                shadow: ShadowSettings::default(),
                effects: Effects::default(),
                objects: vec![object(model, pose)?, table()?],
            },
        ))
    };
    let dense = format!("builtin:sphere:{dense_segments}");
    Ok(vec![
        on_table("box", "builtin:box", turned(0.5, 0.1, 0.2))?,
        on_table("step", "builtin:step", turned(0.35, 0.4, 0.0))?,
        on_table("cylinder", "builtin:cylinder:48", turned(0.2, 0.0, 0.0))?,
        on_table("sphere", "builtin:sphere:48", turned(0.3, 0.0, 0.0))?,
        SweepScene::builtin(
            "cluttered",
            Scene {
                sensor: sensor(size, 5.0),
                shadow: ShadowSettings::default(),
                effects: Effects::default(),
                objects: vec![
                    object("builtin:step", turned(0.35, 0.6, 0.9))?,
                    object("builtin:cylinder:48", turned(0.0, -1.2, -1.1))?,
                    object("builtin:box", turned(-0.5, -1.3, 1.0))?,
                    object("builtin:sphere:48", turned(0.0, 1.1, -1.2))?,
                    table()?,
                ],
            },
        ),
        SweepScene::builtin(
            "dense part",
            Scene {
                sensor: sensor(size, 1.1),
                shadow: ShadowSettings::default(),
                effects: Effects::default(),
                objects: vec![object(&dense, turned(0.3, 0.0, 0.0))?],
            },
        ),
    ])
}

/// `scene` with every curved built-in tessellated with `n` sides or segments; `None` when it
/// has none.
pub fn retessellate(scene: &Scene, n: u32) -> Result<Option<Scene>> {
    let mut changed = false;
    let mut objects = Vec::with_capacity(scene.objects.len());
    for o in &scene.objects {
        match retessellated(&o.model_ref, n)? {
            Some(model) => {
                changed = true;
                objects.push(SceneObject {
                    model_ref: model.clone(),
                    mesh: Arc::new(builtin_mesh(&model)?),
                    ..o.clone()
                });
            }
            None => objects.push(o.clone()),
        }
    }
    Ok(changed.then(|| Scene { objects, ..scene.clone() }))
}
