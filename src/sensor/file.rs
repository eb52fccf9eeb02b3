//! The sensor as files write it: `[sensor]` with its `kind`'s keys, and `[[sensor.witness]]`
//! tables (a hypothesis file's `"sensor"` and a range image's header hold the same keys). A
//! key of another kind, or a kind's key left out, is refused by name.

use super::orthographic::Orthographic;
use super::pinhole::{Intrinsics, Pinhole};
use super::witness::{Direction, Witness, WitnessGeometry};
use super::{Sensor, View, THETA_WITNESS_NAME};
use crate::pose::pose_rows;
use glam::{DMat4, DVec3};
use serde::{Deserialize, Serialize};

#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
enum ReferenceKind {
    Orthographic,
    Pinhole,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
enum WitnessKind {
    Pinhole,
    Directional,
}

#[derive(Debug, Clone, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct SensorFile {
    kind: Option<ReferenceKind>,
    width: Option<u32>,
    height: Option<u32>,
    #[serde(default, deserialize_with = "crate::exact_array::optional_array", skip_serializing_if = "Option::is_none")]
    pitch: Option<[f64; 2]>,
    #[serde(default, deserialize_with = "crate::exact_array::optional_array", skip_serializing_if = "Option::is_none")]
    origin: Option<[f64; 2]>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    theta_deg: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    fx: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    fy: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    cx: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    cy: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    near: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    far: Option<f64>,
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    witness: Vec<WitnessFile>,
}

#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct WitnessFile {
    name: String,
    kind: WitnessKind,
    #[serde(
        default,
        deserialize_with = "crate::exact_array::optional_matrix",
        skip_serializing_if = "Option::is_none"
    )]
    pose: Option<[[f64; 4]; 4]>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    width: Option<u32>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    height: Option<u32>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    fx: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    fy: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    cx: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    cy: Option<f64>,
    #[serde(default, deserialize_with = "crate::exact_array::optional_array", skip_serializing_if = "Option::is_none")]
    direction: Option<[f64; 3]>,
}

/// A key's value, or a refusal naming it as `owner`'s `kind` needs it.
fn needed<T>(value: Option<T>, key: &str, owner: &str, kind: &str) -> Result<T, String> {
    value.ok_or_else(|| format!("{owner} kind = \"{kind}\" needs {key}"))
}

/// Refuses the keys that `kind` does not read: (key, whether it was given).
fn refuse_others(given: &[(&str, bool)], owner: &str, kind: &str) -> Result<(), String> {
    match given.iter().find(|(_, present)| *present) {
        Some((key, _)) => Err(format!("{owner} kind = \"{kind}\" has no key {key}")),
        None => Ok(()),
    }
}

fn intrinsics(
    [width, height]: [Option<u32>; 2],
    [fx, fy, cx, cy]: [Option<f64>; 4],
    owner: &str,
) -> Result<Intrinsics, String> {
    let kind = "pinhole";
    Ok(Intrinsics {
        width: needed(width, "width", owner, kind)?,
        height: needed(height, "height", owner, kind)?,
        fx: needed(fx, "fx", owner, kind)?,
        fy: needed(fy, "fy", owner, kind)?,
        cx: needed(cx, "cx", owner, kind)?,
        cy: needed(cy, "cy", owner, kind)?,
    })
}

impl TryFrom<SensorFile> for Sensor {
    type Error = String;

    fn try_from(f: SensorFile) -> Result<Self, String> {
        let owner = "[sensor]";
        let kind = f.kind.ok_or_else(|| format!("{owner} needs kind (\"orthographic\" or \"pinhole\")"))?;
        let mut witnesses = Vec::new();
        let reference = match kind {
            ReferenceKind::Orthographic => {
                let kind = "orthographic";
                refuse_others(
                    &[
                        ("fx", f.fx.is_some()),
                        ("fy", f.fy.is_some()),
                        ("cx", f.cx.is_some()),
                        ("cy", f.cy.is_some()),
                        ("near", f.near.is_some()),
                        ("far", f.far.is_some()),
                    ],
                    owner,
                    kind,
                )?;
                if let Some(theta_deg) = f.theta_deg {
                    witnesses.push(Witness {
                        name: THETA_WITNESS_NAME.into(),
                        geometry: WitnessGeometry::Directional(Direction::Tilt { theta_deg }),
                    });
                }
                View::Orthographic(Orthographic {
                    width: needed(f.width, "width", owner, kind)?,
                    height: needed(f.height, "height", owner, kind)?,
                    pitch: needed(f.pitch, "pitch", owner, kind)?,
                    origin: needed(f.origin, "origin", owner, kind)?,
                })
            }
            ReferenceKind::Pinhole => {
                refuse_others(
                    &[
                        ("pitch", f.pitch.is_some()),
                        ("origin", f.origin.is_some()),
                        ("theta_deg", f.theta_deg.is_some()),
                    ],
                    owner,
                    "pinhole",
                )?;
                View::Pinhole(Pinhole {
                    intrinsics: intrinsics([f.width, f.height], [f.fx, f.fy, f.cx, f.cy], owner)?,
                    near: f.near.unwrap_or(0.0),
                    far: f.far.unwrap_or(f64::INFINITY),
                })
            }
        };
        let first = witnesses.len();
        for (i, w) in f.witness.into_iter().enumerate() {
            let owner = format!("[[sensor.witness]] {} ({:?})", first + i + 1, w.name);
            let geometry = match w.kind {
                WitnessKind::Pinhole => {
                    refuse_others(&[("direction", w.direction.is_some())], &owner, "pinhole")?;
                    let pose = needed(w.pose, "pose", &owner, "pinhole")?;
                    WitnessGeometry::Pinhole {
                        pose: DMat4::from_cols_array_2d(&pose).transpose(),
                        intrinsics: intrinsics([w.width, w.height], [w.fx, w.fy, w.cx, w.cy], &owner)?,
                    }
                }
                WitnessKind::Directional => {
                    refuse_others(
                        &[
                            ("pose", w.pose.is_some()),
                            ("width", w.width.is_some()),
                            ("height", w.height.is_some()),
                            ("fx", w.fx.is_some()),
                            ("fy", w.fy.is_some()),
                            ("cx", w.cx.is_some()),
                            ("cy", w.cy.is_some()),
                        ],
                        &owner,
                        "directional",
                    )?;
                    let direction = needed(w.direction, "direction", &owner, "directional")?;
                    WitnessGeometry::Directional(Direction::Vector(DVec3::from_array(direction)))
                }
            };
            witnesses.push(Witness { name: w.name, geometry });
        }
        Ok(Sensor { reference, witnesses })
    }
}

impl From<Sensor> for SensorFile {
    fn from(sensor: Sensor) -> Self {
        let mut file = SensorFile::default();
        let mut witnesses = sensor.witnesses.into_iter().peekable();
        match sensor.reference {
            View::Orthographic(o) => {
                file.kind = Some(ReferenceKind::Orthographic);
                (file.width, file.height, file.pitch, file.origin) =
                    (Some(o.width), Some(o.height), Some(o.pitch), Some(o.origin));
                // theta_deg's witness is written as theta_deg, as it was read.
                if let Some(WitnessGeometry::Directional(Direction::Tilt { theta_deg })) =
                    witnesses.peek().map(|w| w.geometry)
                {
                    file.theta_deg = Some(theta_deg);
                    witnesses.next();
                }
            }
            View::Pinhole(p) => {
                let k = p.intrinsics;
                file.kind = Some(ReferenceKind::Pinhole);
                (file.width, file.height) = (Some(k.width), Some(k.height));
                (file.fx, file.fy, file.cx, file.cy) = (Some(k.fx), Some(k.fy), Some(k.cx), Some(k.cy));
                file.near = (p.near != 0.0).then_some(p.near);
                file.far = p.far.is_finite().then_some(p.far);
            }
        }
        file.witness = witnesses
            .map(|w| {
                let mut out = WitnessFile {
                    name: w.name,
                    kind: WitnessKind::Directional,
                    pose: None,
                    width: None,
                    height: None,
                    fx: None,
                    fy: None,
                    cx: None,
                    cy: None,
                    direction: None,
                };
                match w.geometry {
                    WitnessGeometry::Pinhole { pose, intrinsics: k } => {
                        out.kind = WitnessKind::Pinhole;
                        out.pose = Some(pose_rows(&pose));
                        (out.width, out.height) = (Some(k.width), Some(k.height));
                        (out.fx, out.fy, out.cx, out.cy) = (Some(k.fx), Some(k.fy), Some(k.cx), Some(k.cy));
                    }
                    WitnessGeometry::Directional(d) => out.direction = Some(d.vector().to_array()),
                }
                out
            })
            .collect();
        file
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const PINHOLE: &str =
        "kind = \"pinhole\"\nwidth = 640\nheight = 480\nfx = 572.4\nfy = 573.6\ncx = 325.3\ncy = 242.0\n";
    const PROJECTOR: &str = "[[witness]]\nname = \"projector\"\nkind = \"pinhole\"\n\
        pose = [[1, 0, 0, 0.075], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]]\n\
        width = 640\nheight = 480\nfx = 580\nfy = 580\ncx = 320\ncy = 240\n";

    fn read(text: &str) -> Result<Sensor, String> {
        toml::from_str::<Sensor>(text).map_err(|e| e.to_string())
    }

    #[test]
    fn a_pinhole_rig_reads_back_as_it_was_written() {
        let light = "[[witness]]\nname = \"lamp\"\nkind = \"directional\"\ndirection = [0.6, 0.0, 0.8]\n";
        let sensor = read(&format!("{PINHOLE}near = 0.1\n{PROJECTOR}{light}")).unwrap();
        let View::Pinhole(p) = sensor.reference else { panic!("{sensor:?}") };
        assert_eq!((p.intrinsics.fx, p.intrinsics.cy, p.near, p.far), (572.4, 242.0, 0.1, f64::INFINITY));
        assert_eq!(sensor.witnesses.len(), 2);
        let WitnessGeometry::Pinhole { pose, .. } = sensor.witnesses[0].geometry else { panic!() };
        assert_eq!(pose.w_axis, glam::DVec4::new(0.075, 0.0, 0.0, 1.0));
        assert_eq!(sensor.witnesses[1].toward(DVec3::ZERO).0, DVec3::new(0.6, 0.0, 0.8));
        for text in [toml::to_string(&sensor).unwrap(), serde_json::to_string(&sensor).unwrap()] {
            let again: Sensor = match text.starts_with('{') {
                true => serde_json::from_str(&text).unwrap(),
                false => toml::from_str(&text).unwrap(),
            };
            assert_eq!(again, sensor, "{text}");
        }
    }

    /// The paper's scanner is written with today's keys, theta_deg included, and nothing else.
    #[test]
    fn the_scanner_is_written_as_it_always_was() {
        let text = toml::to_string(&Sensor::square(4, 2.0, 30.0)).unwrap();
        assert_eq!(
            text,
            "kind = \"orthographic\"\nwidth = 4\nheight = 4\npitch = [0.5, 0.5]\norigin = [-0.75, 0.75]\ntheta_deg = 30.0\n"
        );
    }

    #[test]
    fn keys_of_another_kind_or_missing_are_refused_by_name() {
        let ortho = "kind = \"orthographic\"\nwidth = 4\nheight = 4\npitch = [0.5, 0.5]\norigin = [0, 0]\n";
        for (text, expected) in [
            (format!("{ortho}fx = 3\n"), "[sensor] kind = \"orthographic\" has no key fx"),
            (format!("{PINHOLE}theta_deg = 30\n"), "[sensor] kind = \"pinhole\" has no key theta_deg"),
            (PINHOLE.replace("fy = 573.6\n", ""), "[sensor] kind = \"pinhole\" needs fy"),
            (ortho.replace("pitch = [0.5, 0.5]\n", ""), "[sensor] kind = \"orthographic\" needs pitch"),
            (PINHOLE.replace("kind = \"pinhole\"\n", ""), "[sensor] needs kind"),
            (
                format!(
                    "{PINHOLE}{}",
                    PROJECTOR.replace("pose = [[1, 0, 0, 0.075], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]]\n", "")
                ),
                "[[sensor.witness]] 1 (\"projector\") kind = \"pinhole\" needs pose",
            ),
            (
                format!("{PINHOLE}{}", PROJECTOR.replace("cx = 320\n", "")),
                "[[sensor.witness]] 1 (\"projector\") kind = \"pinhole\" needs cx",
            ),
            (
                format!(
                    "{PINHOLE}[[witness]]\nname = \"sun\"\nkind = \"directional\"\ndirection = [0, 0, 1]\nfx = 2\n"
                ),
                "[[sensor.witness]] 1 (\"sun\") kind = \"directional\" has no key fx",
            ),
            (
                format!("{PINHOLE}[[witness]]\nname = \"sun\"\nkind = \"directional\"\n"),
                "[[sensor.witness]] 1 (\"sun\") kind = \"directional\" needs direction",
            ),
            (
                format!("{PINHOLE}[[witness]]\nname = \"sun\"\nkind = \"directional\"\ndirection = [0, 1]\n"),
                "exactly 3 values",
            ),
            (format!("{PINHOLE}[[witness]]\nname = \"sun\"\nkind = \"spot\"\n"), "spot"),
            (format!("{PINHOLE}bogus = 1\n"), "bogus"),
        ] {
            let e = read(&text).unwrap_err();
            assert!(e.contains(expected), "{text}\n→ {e}");
        }
        // With theta_deg, the witnesses written after it are numbered after its camera.
        let numbered =
            read(&format!("{ortho}theta_deg = 10\n[[witness]]\nname = \"sun\"\nkind = \"directional\"\n")).unwrap_err();
        assert!(numbered.contains("[[sensor.witness]] 2 (\"sun\")"), "{numbered}");
    }
}
