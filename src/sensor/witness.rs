//! Witnesses: every view besides the reference that must see a point for it to be measured
//! (the paper's rule: visible to the camera *and* to each illumination source). A pinhole
//! witness is a camera or projector centre with its own image; a directional one sends
//! parallel rays (the paper's camera, a distant light). docs/sensors-and-rigs.md.

use super::pinhole::Intrinsics;
use super::scanner::check_theta;
use crate::error::{Error, Result};
use crate::pose::check_rigid;
use glam::{DMat3, DMat4, DVec3};

/// Most witnesses a sensor has: one bit each in the `witness` channel (a u32).
pub const MAX_WITNESSES: usize = 32;

/// How far a directional witness's `direction` may be from unit length.
pub const UNIT_TOLERANCE: f64 = 1e-6;

#[derive(Debug, Clone, PartialEq)]
pub struct Witness {
    pub name: String,
    pub geometry: WitnessGeometry,
}

#[derive(Debug, Clone, Copy, PartialEq)]
#[non_exhaustive]
pub enum WitnessGeometry {
    /// A centre: `pose` is reference-from-witness (its translation the centre in the
    /// reference frame, its rotation the witness's x-right, y-down, z-forward axes), and
    /// `intrinsics` its field of view.
    Pinhole { pose: DMat4, intrinsics: Intrinsics },
    /// Parallel rays, arriving from `Direction` (unit, from the scene toward the witness).
    Directional(Direction),
}

/// A directional witness's direction, as the file gave it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Direction {
    /// `direction = [x, y, z]`.
    Vector(DVec3),
    /// `theta_deg = θ`, the paper's scanner: the camera at `R_y(θ)·(0,0,1)`.
    Tilt { theta_deg: f64 },
}

impl Direction {
    pub fn vector(&self) -> DVec3 {
        match *self {
            Direction::Vector(d) => d,
            Direction::Tilt { theta_deg } => {
                let t = theta_deg.to_radians();
                DVec3::new(t.sin(), 0.0, t.cos())
            }
        }
    }
}

/// A convex region a reference view sees: the points `Σ λᵢ pᵢ + Σ μⱼ dⱼ` with the λ a convex
/// combination and the μ ≥ 0 (its `points` and its unbounded `directions`).
pub struct ViewVolume {
    pub points: Vec<DVec3>,
    pub directions: Vec<DVec3>,
}

impl Witness {
    /// How a refusal names this witness: its place in file order (from 1) and its name.
    pub fn owner(&self, index: usize) -> String {
        format!("[[sensor.witness]] {} ({:?})", index + 1, self.name)
    }

    /// Checks the witness, `index` its place in file order, against the volume its reference
    /// view sees.
    pub fn validate(&self, index: usize, seen: &ViewVolume) -> Result<()> {
        let owner = self.owner(index);
        if self.name.trim().is_empty() {
            return Err(Error::Scene(format!("{owner}: name must not be empty")));
        }
        match self.geometry {
            WitnessGeometry::Pinhole { pose, intrinsics } => {
                check_rigid(&pose, &owner)?;
                intrinsics.validate(&owner)?;
                if !self.may_see(seen) {
                    return Err(Error::Scene(format!(
                        "{owner}: its field of view cannot contain any point the reference view sees; pose is the \
                         reference-from-witness transform (its z axis the witness's optical axis, in the reference \
                         frame)"
                    )));
                }
            }
            WitnessGeometry::Directional(Direction::Vector(d)) => {
                if !(d.is_finite() && (d.length() - 1.0).abs() <= UNIT_TOLERANCE) {
                    return Err(Error::Scene(format!(
                        "{owner}: direction = [{}, {}, {}] must be a finite unit vector",
                        d.x, d.y, d.z
                    )));
                }
            }
            WitnessGeometry::Directional(Direction::Tilt { theta_deg }) => check_theta(theta_deg)?,
        }
        Ok(())
    }

    /// The unit vector from `p` (reference frame) toward this witness, and how far along it
    /// the witness lies (∞ for a directional one).
    pub fn toward(&self, p: DVec3) -> (DVec3, f64) {
        match self.geometry {
            WitnessGeometry::Pinhole { pose, .. } => {
                let offset = pose.w_axis.truncate() - p;
                let distance = offset.length();
                (offset / distance, distance)
            }
            WitnessGeometry::Directional(direction) => (direction.vector(), f64::INFINITY),
        }
    }

    /// Whether `p` (reference frame) lies in this witness's field of view: in front of a
    /// pinhole witness and on its image; everywhere for a directional one.
    pub fn in_view(&self, p: DVec3) -> bool {
        match self.geometry {
            WitnessGeometry::Pinhole { pose, intrinsics } => {
                intrinsics.project(pose.inverse().transform_point3(p)).is_some_and(|uv| intrinsics.contains(uv))
            }
            WitnessGeometry::Directional(_) => true,
        }
    }

    /// Whether any point of `volume` may lie in this witness's field of view: false when the
    /// volume lies wholly outside one of the half-spaces that bound it (behind the witness, or
    /// beyond one side of its image).
    fn may_see(&self, volume: &ViewVolume) -> bool {
        let WitnessGeometry::Pinhole { pose, intrinsics: k } = self.geometry else {
            return true;
        };
        let centre = pose.w_axis.truncate();
        let axes = DMat3::from_mat4(pose);
        let (w, h) = (f64::from(k.width), f64::from(k.height));
        // In the witness's frame: z > 0, and u, v within the image (multiplied through by z).
        let bounds = [
            DVec3::Z,
            DVec3::new(k.fx, 0.0, k.cx + 0.5),
            DVec3::new(-k.fx, 0.0, w - 0.5 - k.cx),
            DVec3::new(0.0, k.fy, k.cy + 0.5),
            DVec3::new(0.0, -k.fy, h - 0.5 - k.cy),
        ];
        !bounds.iter().any(|&bound| {
            let normal = axes * bound;
            volume.points.iter().all(|&p| normal.dot(p - centre) <= 0.0)
                && volume.directions.iter().all(|&d| normal.dot(d) <= 0.0)
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn camera(pose: DMat4) -> Witness {
        let intrinsics = Intrinsics { width: 64, height: 48, fx: 50.0, fy: 50.0, cx: 31.5, cy: 23.5 };
        Witness { name: "ir".into(), geometry: WitnessGeometry::Pinhole { pose, intrinsics } }
    }

    /// A cone from the origin down +z, as a pinhole reference with no near or far limit sees.
    fn cone() -> ViewVolume {
        ViewVolume {
            points: vec![DVec3::ZERO],
            directions: vec![DVec3::new(-0.5, -0.5, 1.0), DVec3::new(0.5, -0.5, 1.0), DVec3::new(0.5, 0.5, 1.0)],
        }
    }

    #[test]
    fn a_point_is_in_a_pinhole_witnesss_view_only_in_front_of_it_and_on_its_image() {
        // 7.5 cm to the reference's right, looking the same way: a point 1 m ahead of the
        // reference is at u = 31.5 + 50·(−0.075)/1 = 27.75.
        let w = camera(DMat4::from_translation(DVec3::new(0.075, 0.0, 0.0)));
        assert!(w.in_view(DVec3::new(0.0, 0.0, 1.0)));
        // Behind it, or off its image to the left (u < −½ needs x − 0.075 < −0.64 at z = 1).
        assert!(!w.in_view(DVec3::new(0.0, 0.0, -1.0)));
        assert!(!w.in_view(DVec3::new(-0.57, 0.0, 1.0)));
        assert!(w.in_view(DVec3::new(-0.56, 0.0, 1.0)));
        let (toward, distance) = w.toward(DVec3::new(0.075, 0.0, 2.0));
        assert!((toward - DVec3::NEG_Z).length() < 1e-15 && (distance - 2.0).abs() < 1e-15);
    }

    /// A witness turned to face back along −z sees nothing of a cone ahead; one turned a
    /// little sees part of it.
    #[test]
    fn a_witness_that_cannot_see_the_reference_volume_is_refused() {
        let ahead = camera(DMat4::IDENTITY);
        assert!(ahead.validate(0, &cone()).is_ok());
        let back = camera(DMat4::from_rotation_y(std::f64::consts::PI));
        let e = back.validate(1, &cone()).unwrap_err().to_string();
        assert!(e.contains("[[sensor.witness]] 2 (\"ir\"): its field of view cannot contain any point"), "{e}");
        assert!(camera(DMat4::from_rotation_y(0.3)).validate(0, &cone()).is_ok());
        // Facing sideways (+x) from 10 units to the left of a cone whose x never goes below −0.5·z:
        // it sees the cone's far part; from 10 units to its right, facing away (+x), nothing.
        let turned = DMat4::from_rotation_y(std::f64::consts::FRAC_PI_2);
        assert!(camera(DMat4::from_translation(DVec3::new(-10.0, 0.0, 0.0)) * turned).validate(0, &cone()).is_ok());
        let away = camera(DMat4::from_translation(DVec3::new(10.0, 0.0, 0.0)) * turned).validate(0, &cone());
        assert!(away.is_err(), "{away:?}");
    }

    #[test]
    fn bad_witnesses_are_refused_by_key() {
        let sheared = DMat4::from_cols_array_2d(&[
            [1.0, 0.1, 0.0, 0.0],
            [0.0, 1.0, 0.0, 0.0],
            [0.0, 0.0, 1.0, 0.0],
            [0.0, 0.0, 0.0, 1.0],
        ]);
        let e = camera(sheared).validate(0, &cone()).unwrap_err().to_string();
        assert!(e.contains("[[sensor.witness]] 1 (\"ir\")") && e.contains("rigid"), "{e}");
        let nan = camera(DMat4::from_translation(DVec3::new(f64::NAN, 0.0, 0.0)));
        let e = nan.validate(0, &cone()).unwrap_err().to_string();
        assert!(e.contains("non-finite"), "{e}");
        let light =
            |d: DVec3| Witness { name: "lamp".into(), geometry: WitnessGeometry::Directional(Direction::Vector(d)) };
        assert!(light(DVec3::new(0.6, 0.0, 0.8)).validate(0, &cone()).is_ok());
        for d in [DVec3::new(0.6, 0.0, 0.9), DVec3::ZERO, DVec3::new(f64::NAN, 0.0, 1.0)] {
            let e = light(d).validate(2, &cone()).unwrap_err().to_string();
            assert!(e.contains("[[sensor.witness]] 3 (\"lamp\"): direction") && e.contains("unit vector"), "{e}");
        }
        let unnamed = Witness { name: " ".into(), ..light(DVec3::Z) };
        assert!(unnamed.validate(0, &cone()).unwrap_err().to_string().contains("name must not be empty"));
    }
}
