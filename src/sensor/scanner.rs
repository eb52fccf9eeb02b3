//! The paper's scanner as the GPU path renders it (docs/design.md): an orthographic range view
//! and one directional witness, the camera, at `d_cam = R_y(θ)·(0,0,1)`. A rig of that shape
//! (`Scanner::scanner`) is the one the GPU shadow modes render today; pure f64 functions, so
//! the conventions are testable without a GPU.
//!
//! Range frame: the sensor looks down −z (larger z is closer); pixel (col c, row r) has its
//! centre at `x = x0 + c·dx`, `y = y0 − r·dy`. The shadow view renders the scene under
//! `R_y(−θ)`, which maps `d_cam` to +z, on a grid with the same pitch and the same rows (a
//! rotation about y leaves y alone), so a range pixel's point lands exactly on a shadow row
//! and only its column is rounded.

use super::grid::ViewGrid;
use super::orthographic::Orthographic;
use super::orthographic::MAX_IMAGE_SIDE;
use crate::error::{Error, Result};
use glam::{DMat4, DVec3};

/// The paper's orthographic laser-stripe scanner: the range view's grid and the triangulation
/// angle θ of its one witness.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Scanner {
    pub width: u32,
    pub height: u32,
    /// dx, dy: model units per pixel.
    pub pitch: [f64; 2],
    /// x, y of the centre of pixel (col 0, row 0).
    pub origin: [f64; 2],
    /// Triangulation angle between projector and camera, degrees, in [−89, 89].
    pub theta_deg: f64,
}

/// Steepest triangulation angle accepted, degrees. Up to it, depth-mode shadows match exact
/// shadowing away from edges (tests/stability.rs); beyond it the camera grazes every surface,
/// the shadow view's columns shrink toward zero width in the range frame, and a cluttered scene
/// at 89.5° already had about 1.5% of its pixels wrong, so steeper angles are refused.
pub const MAX_THETA_DEG: f64 = 89.0;

/// Refuses a triangulation angle beyond [`MAX_THETA_DEG`] (or not finite).
pub(super) fn check_theta(theta_deg: f64) -> Result<()> {
    match theta_deg.is_finite() && theta_deg.abs() <= MAX_THETA_DEG {
        true => Ok(()),
        false => Err(Error::Scene(format!(
            "theta_deg = {theta_deg} must lie between -{MAX_THETA_DEG} and {MAX_THETA_DEG}: steeper angles graze \
             every surface and are not rendered exactly"
        ))),
    }
}

impl Scanner {
    pub fn validate(&self) -> Result<()> {
        self.view().validate()?;
        check_theta(self.theta_deg)
    }

    /// The scanner's range view.
    pub fn view(&self) -> Orthographic {
        Orthographic { width: self.width, height: self.height, pitch: self.pitch, origin: self.origin }
    }

    /// The scanner of an orthographic view whose one witness is the camera at θ.
    pub fn new(view: Orthographic, theta_deg: f64) -> Self {
        let Orthographic { width, height, pitch, origin } = view;
        Self { width, height, pitch, origin, theta_deg }
    }

    /// A `size`×`size` orthographic image over `extent` model units, centred on the range frame's
    /// origin, at θ = `theta_deg`.
    pub fn square(size: u32, extent: f64, theta_deg: f64) -> Self {
        let pitch = extent / f64::from(size);
        let half = (f64::from(size) - 1.0) / 2.0 * pitch;
        Self { width: size, height: size, pitch: [pitch, pitch], origin: [-half, half], theta_deg }
    }

    pub fn theta(&self) -> f64 {
        self.theta_deg.to_radians()
    }

    /// The camera direction `R_y(θ)·(0,0,1)`.
    pub fn camera_direction(&self) -> DVec3 {
        let t = self.theta();
        DVec3::new(t.sin(), 0.0, t.cos())
    }

    /// `R_y(−θ)`: range frame → shadow-view frame.
    pub fn to_shadow_frame(&self) -> DMat4 {
        DMat4::from_rotation_y(-self.theta())
    }

    /// Centre of pixel (col, row) in the range frame's x, y.
    pub fn pixel_centre(&self, col: u32, row: u32) -> (f64, f64) {
        self.view().pixel_centre(col, row)
    }

    /// The range view's grid, with its depth range set to `z_range`.
    pub fn range_grid(&self, z_range: (f64, f64)) -> ViewGrid {
        ViewGrid { origin: self.origin, pitch: self.pitch, width: self.width, height: self.height, z_range }
    }

    /// The shadow view's grid: the range view's rows, and `columns` columns per range pitch
    /// (`[shadow] columns`), which cover the
    /// shadow-frame x of every point the range view can see, i.e. the range image's
    /// footprint at any depth in `z_range` (the range frame's scene depth bounds), rotated
    /// by `R_y(−θ)`. `shadow_z_range` bounds the scene's depth in the shadow frame.
    ///
    /// Column centres lie on one lattice, through the rotated range-grid origin at depth
    /// `lattice_z` (the local origin's z, `ViewGrid::local_origin`), not wherever the depth
    /// range happens to start: the same scene moved with its sensor keeps the same columns,
    /// and so the same nearest shadow pixel for every point.
    pub fn shadow_grid(
        &self,
        z_range: (f64, f64),
        shadow_z_range: (f64, f64),
        lattice_z: f64,
        columns: u32,
    ) -> Result<ViewGrid> {
        let (c, s) = (self.theta().cos(), self.theta().sin());
        let dx = self.pitch[0] / f64::from(columns);
        let half = self.pitch[0] / 2.0;
        let x_lo = self.origin[0] - half;
        let x_hi = self.origin[0] + (f64::from(self.width) - 0.5) * self.pitch[0];
        let xs: Vec<f64> = [(x_lo, z_range.0), (x_lo, z_range.1), (x_hi, z_range.0), (x_hi, z_range.1)]
            .iter()
            .map(|&(x, z)| c * x - s * z)
            .collect();
        let lo = xs.iter().copied().fold(f64::INFINITY, f64::min);
        let hi = xs.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        let anchor = c * self.origin[0] - s * lattice_z;
        // The lattice columns whose pixels reach lo and hi.
        let first = ((lo - anchor) / dx + 0.5).floor();
        let last = ((hi - anchor) / dx - 0.5).ceil();
        let columns = last - first + 1.0;
        // NaN (a depth range that overflowed) is refused too.
        if columns.is_nan() || columns > f64::from(MAX_IMAGE_SIDE) {
            return Err(Error::Scene(format!(
                "the shadow view would need {columns} columns (more than {MAX_IMAGE_SIDE}): the scene's depth \
                 range ({:.4} to {:.4}) is too deep for θ = {}° at pitch {}",
                z_range.0, z_range.1, self.theta_deg, dx
            )));
        }
        Ok(ViewGrid {
            origin: [anchor + first * dx, self.origin[1]],
            pitch: [dx, self.pitch[1]],
            width: columns as u32,
            height: self.height,
            z_range: shadow_z_range,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The bounds worked out from f32's range: a pixel's squared area must lie in
    /// [2^-126, 3.4e38], so dx·dy in [1.08e-19, 1.84e19]; at 1e6 f32 values are 2^-4 apart.
    #[test]
    fn a_grid_is_accepted_exactly_where_f32_holds_it() {
        let with = |pitch: [f64; 2], origin: [f64; 2]| Scanner { pitch, origin, ..Scanner::square(16, 1.0, 0.0) };
        for (pitch, origin, accepted) in [
            ([3.3e-10, 3.3e-10], [0.0, 0.0], true),
            ([3.2e-10, 3.2e-10], [0.0, 0.0], false),
            ([4.2e9, 4.2e9], [0.0, 0.0], true),
            ([4.3e9, 4.3e9], [0.0, 0.0], false),
            ([1e-20, 1e2], [0.0, 0.0], true),
            ([1e-39, 1e20], [0.0, 0.0], false),
            ([0.0625, 0.0625], [1e6, 0.0], true),
            ([0.06, 0.06], [1e6, 0.0], false),
            ([0.0625, 0.0625], [0.0, -1e6], true),
            ([0.06, 0.06], [0.0, -1e6], false),
            // 16 pixels of 1/16 reach 2^20 (where f32 values are 1/8 apart) from 2^20 − 1, one
            // pitch beyond the last centre, rightward along a row or downward along a column.
            ([0.0625, 0.0625], [1_048_574.937_5, 0.0], true),
            ([0.0625, 0.0625], [1_048_575.0, 0.0], false),
            ([0.0625, 0.0625], [0.0, -1_048_574.937_5], true),
            ([0.0625, 0.0625], [0.0, -1_048_575.0], false),
            ([1.0, 1.0], [3.4e38, 0.0], false),
        ] {
            let result = with(pitch, origin).validate();
            assert_eq!(result.is_ok(), accepted, "pitch {pitch:?}, origin {origin:?}: {result:?}");
            if let Err(e) = result {
                let message = e.to_string();
                assert!(message.contains("pitch") || message.contains("origin"), "{message}");
            }
        }
    }

    #[test]
    fn sides_pitches_origins_and_angles_are_accepted_exactly_within_their_limits() {
        let base = Scanner::square(16, 1.0, 0.0);
        // Each refusal is the check's own: a pitch of 0 must not pass for positive and be
        // refused only later as no normal f32.
        let cases = [
            (Scanner { width: 0, ..base }, Some("at least 1")),
            (Scanner { height: 0, ..base }, Some("at least 1")),
            (Scanner { width: MAX_IMAGE_SIDE, pitch: [1e-3, 1e-3], ..base }, None),
            (Scanner { height: MAX_IMAGE_SIDE, pitch: [1e-3, 1e-3], ..base }, None),
            (Scanner { width: MAX_IMAGE_SIDE + 1, pitch: [1e-3, 1e-3], ..base }, Some("limited to 16384")),
            (Scanner { height: MAX_IMAGE_SIDE + 1, pitch: [1e-3, 1e-3], ..base }, Some("limited to 16384")),
            (Scanner { pitch: [0.0, 0.1], ..base }, Some("two positive finite numbers")),
            (Scanner { pitch: [0.1, -0.1], ..base }, Some("two positive finite numbers")),
            (Scanner { pitch: [0.1, f64::NAN], ..base }, Some("two positive finite numbers")),
            (Scanner { pitch: [f64::INFINITY, 0.1], ..base }, Some("two positive finite numbers")),
            (Scanner { origin: [f64::NAN, 0.0], ..base }, Some("must be finite")),
            (Scanner { origin: [0.0, f64::INFINITY], ..base }, Some("must be finite")),
            (Scanner { theta_deg: 89.0, ..base }, None),
            (Scanner { theta_deg: -89.0, ..base }, None),
            (Scanner { theta_deg: 89.001, ..base }, Some("theta_deg")),
            (Scanner { theta_deg: -89.001, ..base }, Some("theta_deg")),
            (Scanner { theta_deg: f64::NAN, ..base }, Some("theta_deg")),
            (Scanner { theta_deg: f64::INFINITY, ..base }, Some("theta_deg")),
        ];
        for (sensor, refusal) in cases {
            match (sensor.validate(), refusal) {
                (Ok(()), None) => {}
                (Err(e), Some(expected)) => assert!(e.to_string().contains(expected), "{sensor:?}: {e}"),
                (result, _) => panic!("{sensor:?}: {result:?}, expected {refusal:?}"),
            }
        }
    }

    #[test]
    fn a_square_sensor_is_centred_on_the_origin() {
        let s = Scanner::square(4, 2.0, 10.0);
        assert_eq!((s.width, s.height, s.pitch, s.origin, s.theta_deg), (4, 4, [0.5, 0.5], [-0.75, 0.75], 10.0));
    }

    #[test]
    fn the_camera_lies_toward_plus_x_and_the_shadow_frame_turns_it_onto_plus_z() {
        let s = Scanner::square(4, 1.0, 30.0);
        let d = s.camera_direction();
        assert!((d - DVec3::new(0.5, 0.0, 3f64.sqrt() / 2.0)).length() < 1e-15, "{d}");
        let turned = s.to_shadow_frame().transform_vector3(d);
        assert!((turned - DVec3::Z).length() < 1e-15, "{turned}");
    }

    #[test]
    fn pixel_centres_step_right_and_down_from_the_origin() {
        let s = Scanner { origin: [1.0, 2.0], pitch: [0.1, 0.2], ..Scanner::square(8, 1.0, 0.0) };
        let (x, y) = s.pixel_centre(3, 4);
        assert!((x - 1.3).abs() < 1e-12 && (y - 1.2).abs() < 1e-12, "({x}, {y})");
        let g = s.range_grid((-1.0, 2.0));
        assert_eq!(g, ViewGrid { origin: [1.0, 2.0], pitch: [0.1, 0.2], width: 8, height: 8, z_range: (-1.0, 2.0) });
    }

    /// θ with cos θ = 0.6 and sin θ = 0.8; a range row of 4 pixels of pitch 1 from x = 0, so
    /// x spans [−0.5, 3.5], and depths in [0, 1]: shadow-frame x = 0.6x − 0.8z spans
    /// [−1.1, 2.1].
    #[test]
    fn the_shadow_grids_columns_cover_the_rotated_footprint_on_their_lattice() {
        let s = Scanner {
            origin: [0.0, 5.0],
            pitch: [1.0, 0.5],
            theta_deg: 0.8f64.asin().to_degrees(),
            ..Scanner::square(4, 4.0, 0.0)
        };
        let shadow_z = (-3.0, 3.0);
        let grid = |lattice_z: f64, columns: u32| {
            let g = s.shadow_grid((0.0, 1.0), shadow_z, lattice_z, columns).unwrap();
            assert_eq!((g.pitch[1], g.height, g.origin[1], g.z_range), (0.5, 4, 5.0, shadow_z));
            (g.origin[0], g.pitch[0], g.width)
        };
        let close = |(x, dx, w): (f64, f64, u32), expected: (f64, f64, u32)| {
            assert!((x - expected.0).abs() < 1e-12 && dx == expected.1 && w == expected.2, "{:?}", (x, dx, w));
        };
        // Lattice through x = 0: columns −1..=2 (the first reaches −1.5, the last 2.5).
        close(grid(0.0, 1), (-1.0, 1.0, 4));
        // Half-pixel columns: −2..=4 at 0.5 apart.
        close(grid(0.0, 2), (-1.0, 0.5, 7));
        // Lattice through the origin rotated at depth 1 (x = −0.8): columns 0..=3 from −0.8.
        close(grid(1.0, 1), (-0.8, 1.0, 4));
        // Seven pixels of pitch 0.4 from x = 1.1 span [0.9, 3.7]: shadow-frame x spans
        // [−0.26, 2.22], and the lattice through 0.6 · 1.1 = 0.66 has columns −2..=4.
        let off = Scanner { origin: [1.1, 0.0], pitch: [0.4, 0.4], width: 7, height: 3, ..s };
        let g = off.shadow_grid((0.0, 1.0), shadow_z, 0.0, 1).unwrap();
        assert!((g.origin[0] + 0.14).abs() < 1e-12 && g.width == 7, "{g:?}");
        // Facing the range view (θ = 0), the shadow view is the range view's columns: the
        // largest image has the largest shadow view.
        let widest = Scanner { origin: [0.0, 0.0], pitch: [0.5, 0.5], ..Scanner::square(MAX_IMAGE_SIDE, 1.0, 0.0) };
        assert_eq!(widest.shadow_grid((0.0, 1.0), shadow_z, 0.0, 1).unwrap().width, MAX_IMAGE_SIDE);
        // Too deep for 16384 columns, or a depth range that overflowed: refused.
        for z_range in [(0.0, 1e5), (0.0, f64::INFINITY)] {
            let e = s.shadow_grid(z_range, shadow_z, 0.0, 1).unwrap_err().to_string();
            assert!(e.contains("columns"), "{e}");
        }
    }
}
