//! The hypothesis file (docs/design.md "Interfaces"): a depth tolerance, optional sensor, shadow and
//! effects settings (src/effects.rs), and hypotheses, each a model, a pose and bindings (scene label, model surface).

use crate::effects::Effects;
use crate::error::{Error, Result};
use crate::io::{parse_json, read_input_text};
use crate::limits::Ledger;
use crate::mesh::{SurfaceChoice, SurfaceRule};
use crate::pose::pose_from_rows;
use crate::sensor::Sensor;
use crate::shadow::ShadowSettings;
use crate::untrusted::quoted;
use glam::DMat4;
use serde::Deserialize;
use std::collections::HashSet;
use std::path::Path;

/// Bytes of memory parsing takes per byte of JSON, at most: each hypothesis' strings, pose and
/// bindings, as parsed and as checked, and its entry in the batch a verification builds; the
/// worst case is a file of short hypotheses (measured: tests/memory.rs).
const JSON_EXPANSION: u64 = 12;

/// Default depth tolerance τ, model units (the paper's 0.1 inch).
pub const DEFAULT_TOLERANCE: f64 = 0.1;

#[derive(Debug, Clone)]
pub struct HypothesisFile {
    pub tolerance: f64,
    pub sensor: Option<Sensor>,
    pub shadow: Option<ShadowSettings>,
    /// The sensor effects the synthetic images get, where the file names them (`{}` names
    /// none).
    pub effects: Option<Effects>,
    pub hypotheses: Vec<HypothesisEntry>,
}

/// One hypothesis as the file gives it; its model is still a reference.
#[derive(Debug, Clone)]
pub struct HypothesisEntry {
    pub id: String,
    pub model: String,
    /// Model units to scene units (`Mesh::scaled`), 1 unless the file gives `"scale"`.
    pub scale: f64,
    /// The model's surfaces (`"surfaces"`, `"crease_deg"`), which its bindings name.
    pub surfaces: SurfaceChoice,
    pub pose: DMat4,
    /// (scene label, model surface) pairs.
    pub bindings: Vec<(u32, u32)>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawFile {
    #[serde(default = "default_tolerance")]
    tolerance: f64,
    sensor: Option<Sensor>,
    shadow: Option<ShadowSettings>,
    effects: Option<Effects>,
    hypotheses: Vec<RawHypothesis>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawHypothesis {
    id: String,
    model: String,
    #[serde(default = "crate::mesh::default_model_scale")]
    scale: f64,
    surfaces: Option<SurfaceRule>,
    crease_deg: Option<f64>,
    #[serde(deserialize_with = "crate::exact_array::matrix")]
    pose: [[f64; 4]; 4],
    #[serde(default)]
    bindings: Vec<(u32, u32)>,
}

fn default_tolerance() -> f64 {
    DEFAULT_TOLERANCE
}

impl HypothesisFile {
    /// Reads a hypothesis file, charged to `ledger`.
    pub fn from_file(path: &Path, ledger: &Ledger) -> Result<Self> {
        let text = read_input_text(path, "hypothesis file", ledger)?;
        Self::from_json(&text, ledger).map_err(|e| match e {
            Error::Scene(reason) => Error::file(path, reason),
            other => other,
        })
    }

    /// Parses a hypothesis file's text, charging what parsing takes to `ledger`.
    pub fn from_json(text: &str, ledger: &Ledger) -> Result<Self> {
        ledger.charge("parsing the hypothesis file", text.len() as u64 * JSON_EXPANSION)?;
        let raw: RawFile = parse_json(text)?;
        if !(raw.tolerance.is_finite() && raw.tolerance >= 0.0) {
            return Err(Error::Scene(format!("tolerance {} must be a finite number ≥ 0", raw.tolerance)));
        }
        if let Some(sensor) = &raw.sensor {
            sensor.validate()?;
        }
        if let Some(effects) = &raw.effects {
            effects.validate()?;
        }
        // Each output line is known by its id alone.
        let mut ids = HashSet::with_capacity(raw.hypotheses.len());
        if let Some(h) = raw.hypotheses.iter().find(|h| !ids.insert(h.id.as_str())) {
            return Err(Error::Scene(format!(
                "hypothesis id {} is used more than once; ids must be unique",
                quoted(&h.id)
            )));
        }
        let hypotheses = raw
            .hypotheses
            .into_iter()
            .map(|h| {
                let owner = format!("hypothesis {}", quoted(&h.id));
                let pose = pose_from_rows(h.pose, &owner)?;
                if let Some(&(scene, surface)) = h.bindings.iter().find(|&&(s, m)| s == 0 || m == 0) {
                    return Err(Error::Scene(format!(
                        "{owner}: binding ({scene}, {surface}) uses label 0, which means \"no data\""
                    )));
                }
                let surfaces = SurfaceChoice::from_keys(h.surfaces, h.crease_deg, &owner)?;
                Ok(HypothesisEntry { id: h.id, model: h.model, scale: h.scale, surfaces, pose, bindings: h.bindings })
            })
            .collect::<Result<Vec<_>>>()?;
        Ok(Self { tolerance: raw.tolerance, sensor: raw.sensor, shadow: raw.shadow, effects: raw.effects, hypotheses })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::limits::MemoryBudget;

    const EMPTY: &str = r#"{"hypotheses": []}"#;

    /// A file without a tolerance takes the documented default, 0.1.
    #[test]
    fn a_file_without_a_tolerance_takes_the_default() {
        let file = HypothesisFile::from_json(EMPTY, &Ledger::default()).unwrap();
        assert_eq!(file.tolerance, 0.1);
    }

    /// A hypothesis' model is at scale 1 unless it gives `"scale"`.
    #[test]
    fn a_hypothesis_takes_its_scale_or_one() {
        let text = r#"{"hypotheses": [
            {"id": "a", "model": "m.ply", "pose": [[1,0,0,0],[0,1,0,0],[0,0,1,0],[0,0,0,1]]},
            {"id": "b", "model": "m.ply", "scale": 0.001, "pose": [[1,0,0,0],[0,1,0,0],[0,0,1,0],[0,0,0,1]]}]}"#;
        let file = HypothesisFile::from_json(text, &Ledger::default()).unwrap();
        assert_eq!(file.hypotheses.iter().map(|h| h.scale).collect::<Vec<_>>(), [1.0, 0.001]);
    }

    /// A negative tolerance is refused by name.
    #[test]
    fn a_negative_tolerance_is_refused() {
        let e = HypothesisFile::from_json(r#"{"tolerance": -1, "hypotheses": []}"#, &Ledger::default()).unwrap_err();
        assert!(e.to_string().contains("tolerance -1 must be a finite number ≥ 0"), "{e}");
    }

    /// A binding with label 0 on either side is refused: 0 means "no data".
    #[test]
    fn a_binding_to_label_0_on_either_side_is_refused() {
        for binding in ["[0, 1]", "[1, 0]"] {
            let text = format!(
                r#"{{"hypotheses": [{{"id": "h", "model": "builtin:box",
                "pose": [[1,0,0,0],[0,1,0,0],[0,0,1,0],[0,0,0,1]], "bindings": [{binding}]}}]}}"#
            );
            let e = HypothesisFile::from_json(&text, &Ledger::default()).unwrap_err().to_string();
            assert!(e.contains("uses label 0"), "{binding}: {e}");
        }
    }

    /// Parsing is charged JSON_EXPANSION bytes a byte of text: a budget one byte short refuses it.
    #[test]
    fn parsing_is_charged_its_expansion() {
        let needed = EMPTY.len() as u64 * JSON_EXPANSION;
        HypothesisFile::from_json(EMPTY, &Ledger::new(MemoryBudget::new(needed))).unwrap();
        let e = HypothesisFile::from_json(EMPTY, &Ledger::new(MemoryBudget::new(needed - 1))).unwrap_err();
        assert!(e.to_string().contains("parsing the hypothesis file"), "{e}");
    }
}
