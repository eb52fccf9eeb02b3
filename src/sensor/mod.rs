//! The sensor: a reference view, where pixels live and range is measured, and the witnesses,
//! every other view that must see a point for it to be measured (the paper's rule: visible
//! to the camera and to each illumination source). docs/sensors-and-rigs.md.
//!
//! A reference view is orthographic (the paper's range image) or pinhole (a camera with
//! intrinsics K, as datasets store depth). The paper's scanner is one rig among others: an
//! orthographic view and one directional witness written as `theta_deg` ([`Scanner`]), which
//! is the shape the GPU shadow modes render; shadow modes `none` and `exact` render any rig
//! (src/exact/).

mod file;
mod grid;
mod orthographic;
mod pinhole;
mod scanner;
mod witness;

pub use grid::{depth_bounds, depth_margin, PixelRect, ViewGrid};
pub use orthographic::{Orthographic, MAX_IMAGE_SIDE};
pub use pinhole::{Intrinsics, Pinhole};
pub use scanner::{Scanner, MAX_THETA_DEG};
pub use witness::{Direction, ViewVolume, Witness, WitnessGeometry, MAX_WITNESSES};

use crate::error::{Error, Result};
use glam::DVec3;
use serde::{Deserialize, Serialize};

/// The sensor of a scene file's `[sensor]` table, a hypothesis file's `"sensor"` and a range
/// image's header: a reference view and its witnesses, in file order (witness k is bit k of
/// the `witness` channel).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "file::SensorFile", into = "file::SensorFile")]
pub struct Sensor {
    pub reference: View,
    pub witnesses: Vec<Witness>,
}

/// Where pixels live and range is measured.
#[derive(Debug, Clone, Copy, PartialEq)]
#[non_exhaustive]
pub enum View {
    Orthographic(Orthographic),
    Pinhole(Pinhole),
}

impl View {
    /// Width and height in pixels.
    pub fn size(&self) -> (u32, u32) {
        match self {
            View::Orthographic(o) => (o.width, o.height),
            View::Pinhole(p) => (p.intrinsics.width, p.intrinsics.height),
        }
    }

    /// Its `kind` in files.
    pub fn kind(&self) -> &'static str {
        match self {
            View::Orthographic(_) => "orthographic",
            View::Pinhole(_) => "pinhole",
        }
    }

    pub fn validate(&self) -> Result<()> {
        match self {
            View::Orthographic(o) => o.validate(),
            View::Pinhole(p) => p.validate(),
        }
    }

    /// The view as the shaders' view functions take it (shaders/common/view.glsl): its kind's
    /// code and its grid, (x0, y0, dx, dy) of an orthographic view, (fx, fy, cx, cy) of a
    /// pinhole one.
    pub(crate) fn shader_view(&self) -> (u32, [f64; 4]) {
        use crate::shader_contract::{VIEW_ORTHOGRAPHIC, VIEW_PINHOLE};
        match self {
            View::Orthographic(o) => (VIEW_ORTHOGRAPHIC, [o.origin[0], o.origin[1], o.pitch[0], o.pitch[1]]),
            View::Pinhole(p) => {
                let k = &p.intrinsics;
                (VIEW_PINHOLE, [k.fx, k.fy, k.cx, k.cy])
            }
        }
    }

    /// The point (reference frame) on the ray of pixel (col, row) at depth `z`: the range
    /// frame's z of an orthographic view, the depth along the optical axis of a pinhole one.
    pub fn point(&self, col: u32, row: u32, z: f64) -> DVec3 {
        match self {
            View::Orthographic(o) => {
                let (x, y) = o.pixel_centre(col, row);
                DVec3::new(x, y, z)
            }
            View::Pinhole(p) => z * p.intrinsics.ray(col, row),
        }
    }

    /// The pixels whose rays can meet a sphere, with `margin` more each way, clipped to the
    /// image; `None` where none can. An orthographic view's are the sphere's xy box over its
    /// grid; a pinhole view's hold the projections of the cube around the sphere (a convex
    /// set's projection lies within its hull's), or are the whole image where the sphere
    /// reaches the plane of the view's centre (Z ≤ 0), which has no projection, and none where
    /// it lies wholly behind that plane.
    pub fn footprint(&self, centre: DVec3, radius: f64, margin: u32) -> Option<PixelRect> {
        match self {
            View::Orthographic(o) => {
                let grid = ViewGrid {
                    origin: o.origin,
                    pitch: o.pitch,
                    width: o.width,
                    height: o.height,
                    z_range: (0.0, 1.0),
                };
                grid.footprint(centre, radius, margin)
            }
            View::Pinhole(p) => {
                let k = &p.intrinsics;
                let full = PixelRect { col: 0, row: 0, width: k.width, height: k.height };
                if centre.z + radius <= 0.0 {
                    return None; // wholly behind the view
                }
                // (A NaN centre has no projection either.)
                if centre.z - radius <= 0.0 || centre.is_nan() || radius.is_nan() {
                    return Some(full);
                }
                let corners = (0..8).map(|i| {
                    let sign = |bit: u32| if i & bit == 0 { -1.0 } else { 1.0 };
                    centre + radius * DVec3::new(sign(1), sign(2), sign(4))
                });
                let (lo, hi) = corners
                    .filter_map(|c| k.project(c))
                    .fold((glam::DVec2::INFINITY, glam::DVec2::NEG_INFINITY), |(lo, hi), uv| (lo.min(uv), hi.max(uv)));
                let m = f64::from(margin);
                let span = |lo: f64, hi: f64, n: u32| {
                    let (lo, hi) = ((lo.floor() - m).max(0.0), (hi.ceil() + m).min(f64::from(n) - 1.0));
                    (lo <= hi).then(|| (lo as u32, (hi - lo) as u32 + 1))
                };
                let ((col, width), (row, height)) = (span(lo.x, hi.x, k.width)?, span(lo.y, hi.y, k.height)?);
                Some(PixelRect { col, row, width, height })
            }
        }
    }

    /// The region this view sees: an orthographic view's pixels' prism, unbounded both ways
    /// along z; a pinhole view's frustum between near and far.
    pub fn volume(&self) -> ViewVolume {
        match self {
            View::Orthographic(o) => {
                let (x0, y0) = (o.origin[0] - o.pitch[0] / 2.0, o.origin[1] + o.pitch[1] / 2.0);
                let (x1, y1) = (x0 + f64::from(o.width) * o.pitch[0], y0 - f64::from(o.height) * o.pitch[1]);
                ViewVolume {
                    points: [(x0, y0), (x1, y0), (x1, y1), (x0, y1)].map(|(x, y)| DVec3::new(x, y, 0.0)).to_vec(),
                    directions: vec![DVec3::Z, DVec3::NEG_Z],
                }
            }
            View::Pinhole(p) => {
                let rays = p.intrinsics.corner_rays();
                let mut points: Vec<DVec3> = rays.iter().map(|&r| p.near * r).collect();
                let mut directions = Vec::new();
                match p.far.is_finite() {
                    true => points.extend(rays.iter().map(|&r| p.far * r)),
                    false => directions.extend(rays),
                }
                ViewVolume { points, directions }
            }
        }
    }
}

impl Sensor {
    pub fn validate(&self) -> Result<()> {
        self.reference.validate()?;
        if self.witnesses.len() > MAX_WITNESSES {
            return Err(Error::Scene(format!(
                "[sensor] has {} witnesses; at most {MAX_WITNESSES} (one bit each of the witness channel)",
                self.witnesses.len()
            )));
        }
        let volume = self.reference.volume();
        for (i, witness) in self.witnesses.iter().enumerate() {
            witness.validate(i, &volume)?;
            if let Some(first) = self.witnesses[..i].iter().position(|w| w.name == witness.name) {
                return Err(Error::Scene(format!(
                    "{}: name {:?} is witness {}'s already; each witness needs a name of its own",
                    witness.owner(i),
                    witness.name,
                    first + 1
                )));
            }
        }
        Ok(())
    }

    pub fn width(&self) -> u32 {
        self.reference.size().0
    }

    pub fn height(&self) -> u32 {
        self.reference.size().1
    }

    /// The paper's scanner, where this sensor is one: an orthographic view and `theta_deg`.
    pub fn scanner(&self) -> Option<Scanner> {
        match (&self.reference, self.witnesses.as_slice()) {
            (View::Orthographic(view), [only]) => match only.geometry {
                WitnessGeometry::Directional(Direction::Tilt { theta_deg }) => Some(Scanner::new(*view, theta_deg)),
                _ => None,
            },
            _ => None,
        }
    }

    /// The paper's scanner, for `what` (a shadow mode, effects, verification) that the GPU
    /// renders for it alone so far; other rigs are refused, saying what renders them.
    pub fn require_scanner(&self, what: &str) -> Result<Scanner> {
        self.scanner().ok_or_else(|| {
            Error::Scene(format!(
                "{what} renders the paper's scanner (an orthographic [sensor] with theta_deg and no \
                 [[sensor.witness]]) only so far; this sensor has a {} reference view and {} witnesses: render it \
                 with [shadow] mode = \"exact\", \"depth\" or \"none\"",
                self.reference.kind(),
                self.witnesses.len()
            ))
        })
    }

    /// The same rig in units `factor` times smaller (a rig in metres, with `factor` 1000, in
    /// millimetres): every length times `factor` (witness centres, near and far, an
    /// orthographic view's pitch and origin); angles, directions and pixels unchanged.
    pub fn scaled(&self, factor: f64) -> Sensor {
        let reference = match self.reference {
            View::Orthographic(o) => View::Orthographic(Orthographic {
                pitch: o.pitch.map(|p| p * factor),
                origin: o.origin.map(|p| p * factor),
                ..o
            }),
            View::Pinhole(p) => View::Pinhole(Pinhole { near: p.near * factor, far: p.far * factor, ..p }),
        };
        let witnesses = self
            .witnesses
            .iter()
            .map(|w| {
                let geometry = match w.geometry {
                    WitnessGeometry::Pinhole { pose, intrinsics } => {
                        let mut pose = pose;
                        pose.w_axis = (pose.w_axis.truncate() * factor).extend(1.0);
                        WitnessGeometry::Pinhole { pose, intrinsics }
                    }
                    directional => directional,
                };
                Witness { name: w.name.clone(), geometry }
            })
            .collect();
        Sensor { reference, witnesses }
    }

    /// A `size`×`size` orthographic scanner over `extent` model units, centred on the range
    /// frame's origin, at θ = `theta_deg`.
    pub fn square(size: u32, extent: f64, theta_deg: f64) -> Self {
        Scanner::square(size, extent, theta_deg).into()
    }
}

/// The name `theta_deg`'s witness, the paper's camera, gets.
pub const THETA_WITNESS_NAME: &str = "camera";

impl From<Scanner> for Sensor {
    fn from(scanner: Scanner) -> Self {
        let camera = Witness {
            name: THETA_WITNESS_NAME.into(),
            geometry: WitnessGeometry::Directional(Direction::Tilt { theta_deg: scanner.theta_deg }),
        };
        Sensor { reference: View::Orthographic(scanner.view()), witnesses: vec![camera] }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DMat4;

    fn pinhole() -> View {
        let intrinsics = Intrinsics { width: 4, height: 2, fx: 2.0, fy: 2.0, cx: 1.5, cy: 0.5 };
        View::Pinhole(Pinhole { intrinsics, near: 0.0, far: f64::INFINITY })
    }

    /// Scaling a rig multiplies its lengths alone: a witness's centre and the near and far
    /// limits, not its rotation, direction or pixels.
    #[test]
    fn a_scaled_rig_multiplies_its_lengths_alone() {
        let turn = DMat4::from_rotation_y(0.3);
        let witness = |geometry| Witness { name: "w".into(), geometry };
        let k = Intrinsics { width: 4, height: 2, fx: 2.0, fy: 2.0, cx: 1.5, cy: 0.5 };
        let rig = Sensor {
            reference: View::Pinhole(Pinhole { intrinsics: k, near: 0.4, far: 5.0 }),
            witnesses: vec![
                witness(WitnessGeometry::Pinhole {
                    pose: DMat4::from_translation(DVec3::new(0.075, 0.0, 0.0)) * turn,
                    intrinsics: k,
                }),
                witness(WitnessGeometry::Directional(Direction::Vector(DVec3::Y))),
            ],
        };
        let mm = rig.scaled(1000.0);
        assert_eq!(mm.reference, View::Pinhole(Pinhole { intrinsics: k, near: 400.0, far: 5000.0 }));
        let expected = DMat4::from_translation(DVec3::new(75.0, 0.0, 0.0)) * turn;
        match mm.witnesses[0].geometry {
            WitnessGeometry::Pinhole { pose, intrinsics } => {
                assert!(pose.abs_diff_eq(expected, 1e-12) && intrinsics == k, "{pose:?}")
            }
            other => panic!("{other:?}"),
        }
        assert_eq!(mm.witnesses[1], rig.witnesses[1]);
    }

    /// A pinhole view's footprint holds every pixel whose ray meets the sphere: a sphere of
    /// radius 0.5 at (0, 0, 4) under fx = fy = 2, (cx, cy) = (1.5, 0.5) projects within
    /// u, v = 1.5 ± 2·0.5/3.5 and 0.5 ± 2·0.5/3.5 (its cube's nearest face at Z = 3.5): columns
    /// 1..=2 and rows 0..=1, one more each way with margin 1, clipped to the 4×2 image. A sphere
    /// reaching Z ≤ 0 has the whole image; one wholly behind the view, or beside it, none.
    #[test]
    fn a_pinhole_footprint_holds_the_projected_sphere() {
        let view = pinhole();
        let rect = |col, row, width, height| Some(PixelRect { col, row, width, height });
        assert_eq!(view.footprint(DVec3::new(0.0, 0.0, 4.0), 0.5, 0), rect(1, 0, 2, 2));
        assert_eq!(view.footprint(DVec3::new(0.0, 0.0, 4.0), 0.5, 1), rect(0, 0, 4, 2));
        assert_eq!(view.footprint(DVec3::new(0.0, 0.0, 0.2), 0.5, 0), rect(0, 0, 4, 2));
        assert_eq!(view.footprint(DVec3::new(40.0, 0.0, 4.0), 0.5, 1), None);
        assert_eq!(view.footprint(DVec3::new(0.0, 0.0, -0.6), 0.5, 1), None);
    }

    /// Orthographic points lie over their pixel centres at z; pinhole ones at depth Z along
    /// the pixel's ray: pixel (3, 1) of fx = fy = 2, (cx, cy) = (1.5, 0.5) at Z = 4 is
    /// (4·1.5/2, 4·0.5/2, 4).
    #[test]
    fn a_pixels_point_lies_on_its_ray_at_its_depth() {
        let scanner = Scanner::square(4, 4.0, 0.0);
        let ortho = View::Orthographic(scanner.view());
        assert_eq!(ortho.point(0, 3, 2.0), DVec3::new(-1.5, -1.5, 2.0));
        assert_eq!(pinhole().point(3, 1, 4.0), DVec3::new(3.0, 1.0, 4.0));
    }

    #[test]
    fn the_scanner_is_an_orthographic_view_and_theta_alone() {
        let scanner = Scanner::square(8, 1.0, 30.0);
        let sensor = Sensor::from(scanner);
        assert_eq!(sensor.scanner(), Some(scanner));
        assert_eq!(sensor.witnesses[0].name, "camera");
        let d = sensor.witnesses[0].toward(DVec3::ZERO).0;
        assert!((d - DVec3::new(0.5, 0.0, 3f64.sqrt() / 2.0)).length() < 1e-15, "{d}");
        let mut two = sensor.clone();
        two.witnesses.push(Witness { name: "lamp".into(), ..sensor.witnesses[0].clone() });
        assert_eq!(two.scanner(), None);
        let e = two.require_scanner("shadow mode \"label\"").unwrap_err().to_string();
        assert!(e.contains("shadow mode \"label\"") && e.contains("2 witnesses") && e.contains("exact"), "{e}");
        let seen_by_pinhole = Sensor { reference: pinhole(), ..sensor };
        assert_eq!(seen_by_pinhole.scanner(), None);
    }

    #[test]
    fn witnesses_are_counted_and_named_once() {
        let light = |name: &str| Witness {
            name: name.into(),
            geometry: WitnessGeometry::Directional(Direction::Vector(DVec3::Z)),
        };
        let sensor =
            |n: usize| Sensor { reference: pinhole(), witnesses: (0..n).map(|i| light(&format!("l{i}"))).collect() };
        assert!(sensor(MAX_WITNESSES).validate().is_ok());
        let e = sensor(MAX_WITNESSES + 1).validate().unwrap_err().to_string();
        assert!(e.contains("33 witnesses") && e.contains("at most 32"), "{e}");
        let twice = Sensor { reference: pinhole(), witnesses: vec![light("a"), light("b"), light("a")] };
        let e = twice.validate().unwrap_err().to_string();
        assert!(e.contains("[[sensor.witness]] 3 (\"a\")") && e.contains("witness 1's"), "{e}");
        // A witness at the reference's own centre, looking its way, is allowed (it sees what
        // the reference sees, so it loses nothing but its field of view's edges).
        let intrinsics = Intrinsics { width: 4, height: 2, fx: 2.0, fy: 2.0, cx: 1.5, cy: 0.5 };
        let same =
            Witness { name: "same".into(), geometry: WitnessGeometry::Pinhole { pose: DMat4::IDENTITY, intrinsics } };
        assert!(Sensor { reference: pinhole(), witnesses: vec![same] }.validate().is_ok());
    }

    /// A pinhole view sees a cone from its centre through its image's corners (cut at near and
    /// far where they are set); an orthographic one its pixels' prism.
    #[test]
    fn a_views_volume_spans_its_image() {
        let volume = pinhole().volume();
        assert_eq!(volume.points, vec![DVec3::ZERO; 4]);
        assert_eq!(volume.directions[0], DVec3::new(-1.0, -0.5, 1.0));
        assert_eq!(volume.directions[2], DVec3::new(1.0, 0.5, 1.0));
        let View::Pinhole(p) = pinhole() else { unreachable!() };
        let bounded = View::Pinhole(Pinhole { near: 1.0, far: 2.0, ..p }).volume();
        assert_eq!((bounded.points.len(), bounded.directions.len()), (8, 0));
        assert_eq!(bounded.points[6], DVec3::new(2.0, 1.0, 2.0));
        let ortho = View::Orthographic(Scanner::square(4, 4.0, 0.0).view()).volume();
        assert_eq!(ortho.points[0], DVec3::new(-2.0, 2.0, 0.0));
        assert_eq!(ortho.points[2], DVec3::new(2.0, -2.0, 0.0));
    }
}
