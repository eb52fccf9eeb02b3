//! Sensor geometry: the orthographic range image of docs/design.md and the shadow view derived
//! from it. Pure f64 functions, so the conventions are testable without a GPU.
//!
//! Range frame: the sensor looks down −z (larger z is closer); pixel (col c, row r) has its
//! centre at `x = x0 + c·dx`, `y = y0 − r·dy`. The camera direction is
//! `d_cam = R_y(θ)·(0,0,1)`; the shadow view renders the scene under `R_y(−θ)`, which maps
//! `d_cam` to +z, on a grid with the same pitch and the same rows (a rotation about y leaves
//! y alone), so a range pixel's point lands exactly on a shadow row and only its column is
//! rounded.

use crate::error::{Error, Result};
use glam::{DMat4, DVec3};
use serde::{Deserialize, Serialize};

/// The sensor settings of a scene file's `[sensor]` table.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Sensor {
    /// Only `"orthographic"` (the paper's laser-stripe scanner) is implemented.
    pub kind: SensorKind,
    pub width: u32,
    pub height: u32,
    /// dx, dy: model units per pixel.
    #[serde(deserialize_with = "crate::exact_array::array")]
    pub pitch: [f64; 2],
    /// x, y of the centre of pixel (col 0, row 0).
    #[serde(deserialize_with = "crate::exact_array::array")]
    pub origin: [f64; 2],
    /// Triangulation angle between projector and camera, degrees, in [−89, 89].
    pub theta_deg: f64,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum SensorKind {
    Orthographic,
}

/// Largest image side accepted before asking the device (lavapipe allows 16384).
pub const MAX_IMAGE_SIDE: u32 = 16384;

/// Steepest triangulation angle accepted, degrees. Up to it, depth-mode shadows match exact
/// shadowing away from edges (tests/stability.rs); beyond it the camera grazes every surface,
/// the shadow view's columns shrink toward zero width in the range frame, and a cluttered scene
/// at 89.5° already had about 1.5% of its pixels wrong, so steeper angles are refused.
pub const MAX_THETA_DEG: f64 = 89.0;

impl Sensor {
    pub fn validate(&self) -> Result<()> {
        let bad = |m: String| Err(Error::Scene(m));
        if self.width == 0 || self.height == 0 {
            return bad(format!("the image is {}×{} pixels; both sides must be at least 1", self.width, self.height));
        }
        if self.width > MAX_IMAGE_SIDE || self.height > MAX_IMAGE_SIDE {
            return bad(format!(
                "the image is {}×{} pixels; sides are limited to {MAX_IMAGE_SIDE}",
                self.width, self.height
            ));
        }
        if !self.pitch.iter().all(|p| p.is_finite() && *p > 0.0) {
            return bad(format!("pitch {:?} must be two positive finite numbers", self.pitch));
        }
        if !self.origin.iter().all(|o| o.is_finite()) {
            return bad(format!("origin {:?} must be finite", self.origin));
        }
        self.check_in_f32()?;
        if !(self.theta_deg.is_finite() && self.theta_deg.abs() <= MAX_THETA_DEG) {
            return bad(format!(
                "theta_deg = {} must lie between -{MAX_THETA_DEG} and {MAX_THETA_DEG}: steeper angles graze every \
                 surface and are not rendered exactly",
                self.theta_deg
            ));
        }
        Ok(())
    }

    /// The grid as the GPU and the files hold it, in f32 (shaders/raster/draw.glsl's grid,
    /// range.exr's X and Y, the score's areas in src/verify/area.rs): each pitch a normal f32,
    /// a pixel's squared area (dx·dy)² too (a block's area sums it under a square root, and a
    /// GPU may flush a subnormal to zero), and every pixel centre a finite f32 at most a pitch
    /// from its neighbours' values, so that no two columns or rows share a coordinate and the
    /// local origins the GPU measures from (`ViewGrid::local_origin`) stay exact.
    fn check_in_f32(&self) -> Result<()> {
        let [dx, dy] = self.pitch.map(|p| p as f32);
        let squared_area = (dx * dy) * (dx * dy);
        if !(dx.is_normal() && dy.is_normal() && squared_area.is_normal()) {
            return Err(Error::Scene(format!(
                "pitch {:?} is outside what the GPU's f32 arithmetic holds: each pitch must be a normal f32 \
                 (at least {:e}) and a pixel's area dx·dy lie between about 1.1e-19 and 1.8e19, as its \
                 square must be a normal f32 too",
                self.pitch,
                f32::MIN_POSITIVE
            )));
        }
        let sides = [
            (self.origin[0], self.pitch[0], self.width, "column"),
            (self.origin[1], -self.pitch[1], self.height, "row"),
        ];
        for (first, step, count, what) in sides {
            let last = first + f64::from(count - 1) * step;
            let farthest = (first.abs().max(last.abs()) + step.abs()) as f32;
            let spacing = f32::from_bits(farthest.to_bits().saturating_add(1)) - farthest;
            if !farthest.is_finite() {
                return Err(Error::Scene(format!(
                    "origin {:?} and pitch {:?} put the image's last {what} beyond f32's range (the GPU's, \
                     range.exr's X and Y)",
                    self.origin, self.pitch
                )));
            }
            if f64::from(spacing) > step.abs() {
                return Err(Error::Scene(format!(
                    "origin {:?} lies too far from the range frame's origin for pitch {:?}: f32 coordinates (the \
                     GPU's, range.exr's X and Y) are {spacing:e} apart out there, more than a {what}'s pitch, \
                     so pixels would share coordinates; move the range frame nearer the scene",
                    self.origin, self.pitch
                )));
            }
        }
        Ok(())
    }

    /// A `size`×`size` orthographic image over `extent` model units, centred on the range frame's
    /// origin, at θ = `theta_deg`.
    pub fn square(size: u32, extent: f64, theta_deg: f64) -> Self {
        let pitch = extent / f64::from(size);
        let half = (f64::from(size) - 1.0) / 2.0 * pitch;
        Self {
            kind: SensorKind::Orthographic,
            width: size,
            height: size,
            pitch: [pitch, pitch],
            origin: [-half, half],
            theta_deg,
        }
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
        (self.origin[0] + f64::from(col) * self.pitch[0], self.origin[1] - f64::from(row) * self.pitch[1])
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

/// One rendered view: an orthographic grid looking down −z, and the depth range mapped onto
/// the depth buffer (larger z is closer, so it maps to smaller depth; shaders/raster/raster.vert).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ViewGrid {
    pub origin: [f64; 2],
    pub pitch: [f64; 2],
    pub width: u32,
    pub height: u32,
    pub z_range: (f64, f64),
}

/// A rectangle of pixels: columns `col..col + width`, rows `row..row + height`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct PixelRect {
    pub col: u32,
    pub row: u32,
    pub width: u32,
    pub height: u32,
}

impl ViewGrid {
    /// Every pixel of the grid.
    pub fn full(&self) -> PixelRect {
        PixelRect { col: 0, row: 0, width: self.width, height: self.height }
    }

    /// The point (this view's frame) the GPU measures from, so that the same geometry keeps
    /// the same f32 precision wherever it sits: coordinates sent to shaders are offsets from
    /// it, composed in f64. It is the grid's centre snapped to a multiple of the power of two
    /// at least the view's extent, so a view near the frame's origin keeps the origin (and
    /// its images bit for bit), and it is exact in f32, so adding it back to an f32 offset is
    /// one correctly rounded f32 addition on the host or the GPU alike.
    pub fn local_origin(&self) -> DVec3 {
        let [x0, y0] = self.origin;
        let [dx, dy] = self.pitch;
        let (w, h) = (f64::from(self.width), f64::from(self.height));
        let (z0, z1) = self.z_range;
        let centre = DVec3::new(x0 + (w - 1.0) / 2.0 * dx, y0 - (h - 1.0) / 2.0 * dy, (z0 + z1) / 2.0);
        let extent = (w * dx).max(h * dy).max(z1 - z0).max(f64::MIN_POSITIVE);
        let step = extent.log2().ceil().exp2();
        ((centre / step).round() * step).as_vec3().as_dvec3()
    }

    /// How far a sphere (centre in this view's frame) reaches from the grid's first pixel
    /// centre, in pixels along a row or a column, whichever is farther.
    pub fn reach(&self, centre: DVec3, radius: f64) -> f64 {
        let [x0, y0] = self.origin;
        let [dx, dy] = self.pitch;
        (((centre.x - x0).abs() + radius) / dx).max(((y0 - centre.y).abs() + radius) / dy)
    }

    /// The pixels whose centres may fall on a sphere's orthographic footprint (centre in this
    /// view's frame), grown by `margin` pixels on every side and clipped to the grid; `None`
    /// when it misses the grid.
    pub fn footprint(&self, centre: DVec3, radius: f64, margin: u32) -> Option<PixelRect> {
        let [x0, y0] = self.origin;
        let [dx, dy] = self.pitch;
        let m = f64::from(margin);
        let cols = (((centre.x - radius - x0) / dx).floor() - m, ((centre.x + radius - x0) / dx).ceil() + m);
        let rows = (((y0 - centre.y - radius) / dy).floor() - m, ((y0 - centre.y + radius) / dy).ceil() + m);
        let clip = |(lo, hi): (f64, f64), n: u32| {
            let (lo, hi) = (lo.max(0.0), hi.min(f64::from(n) - 1.0));
            (lo <= hi).then(|| (lo as u32, (hi - lo) as u32 + 1))
        };
        let ((col, width), (row, height)) = (clip(cols, self.width)?, clip(rows, self.height)?);
        Some(PixelRect { col, row, width, height })
    }
}

/// Depth bounds along z of spheres (centre, radius), widened by 1% and a small absolute
/// margin so nothing sits on the near or far plane. An empty set gives (−1, 1).
pub fn depth_bounds(spheres: impl IntoIterator<Item = (DVec3, f64)>) -> (f64, f64) {
    let (lo, hi) = spheres
        .into_iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), (c, r)| (lo.min(c.z - r), hi.max(c.z + r)));
    if lo > hi {
        return (-1.0, 1.0);
    }
    let margin = 0.01 * (hi - lo) + 1e-6 * (1.0 + lo.abs().max(hi.abs()));
    (lo - margin, hi + margin)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn grid() -> ViewGrid {
        ViewGrid { origin: [0.0, 0.0], pitch: [0.1, 0.1], width: 100, height: 50, z_range: (-1.0, 1.0) }
    }

    /// The bounds worked out from f32's range: a pixel's squared area must lie in
    /// [2^-126, 3.4e38], so dx·dy in [1.08e-19, 1.84e19]; at 1e6 f32 values are 2^-4 apart.
    #[test]
    fn a_grid_is_accepted_exactly_where_f32_holds_it() {
        let with = |pitch: [f64; 2], origin: [f64; 2]| Sensor { pitch, origin, ..Sensor::square(16, 1.0, 0.0) };
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
        let base = Sensor::square(16, 1.0, 0.0);
        // Each refusal is the check's own: a pitch of 0 must not pass for positive and be
        // refused only later as no normal f32.
        let cases = [
            (Sensor { width: 0, ..base }, Some("at least 1")),
            (Sensor { height: 0, ..base }, Some("at least 1")),
            (Sensor { width: MAX_IMAGE_SIDE, pitch: [1e-3, 1e-3], ..base }, None),
            (Sensor { height: MAX_IMAGE_SIDE, pitch: [1e-3, 1e-3], ..base }, None),
            (Sensor { width: MAX_IMAGE_SIDE + 1, pitch: [1e-3, 1e-3], ..base }, Some("limited to 16384")),
            (Sensor { height: MAX_IMAGE_SIDE + 1, pitch: [1e-3, 1e-3], ..base }, Some("limited to 16384")),
            (Sensor { pitch: [0.0, 0.1], ..base }, Some("two positive finite numbers")),
            (Sensor { pitch: [0.1, -0.1], ..base }, Some("two positive finite numbers")),
            (Sensor { pitch: [0.1, f64::NAN], ..base }, Some("two positive finite numbers")),
            (Sensor { pitch: [f64::INFINITY, 0.1], ..base }, Some("two positive finite numbers")),
            (Sensor { origin: [f64::NAN, 0.0], ..base }, Some("must be finite")),
            (Sensor { origin: [0.0, f64::INFINITY], ..base }, Some("must be finite")),
            (Sensor { theta_deg: 89.0, ..base }, None),
            (Sensor { theta_deg: -89.0, ..base }, None),
            (Sensor { theta_deg: 89.001, ..base }, Some("theta_deg")),
            (Sensor { theta_deg: -89.001, ..base }, Some("theta_deg")),
            (Sensor { theta_deg: f64::NAN, ..base }, Some("theta_deg")),
            (Sensor { theta_deg: f64::INFINITY, ..base }, Some("theta_deg")),
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
        let s = Sensor::square(4, 2.0, 10.0);
        assert_eq!((s.width, s.height, s.pitch, s.origin, s.theta_deg), (4, 4, [0.5, 0.5], [-0.75, 0.75], 10.0));
    }

    #[test]
    fn the_camera_lies_toward_plus_x_and_the_shadow_frame_turns_it_onto_plus_z() {
        let s = Sensor::square(4, 1.0, 30.0);
        let d = s.camera_direction();
        assert!((d - DVec3::new(0.5, 0.0, 3f64.sqrt() / 2.0)).length() < 1e-15, "{d}");
        let turned = s.to_shadow_frame().transform_vector3(d);
        assert!((turned - DVec3::Z).length() < 1e-15, "{turned}");
    }

    #[test]
    fn pixel_centres_step_right_and_down_from_the_origin() {
        let s = Sensor { origin: [1.0, 2.0], pitch: [0.1, 0.2], ..Sensor::square(8, 1.0, 0.0) };
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
        let s = Sensor {
            origin: [0.0, 5.0],
            pitch: [1.0, 0.5],
            theta_deg: 0.8f64.asin().to_degrees(),
            ..Sensor::square(4, 4.0, 0.0)
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
        let off = Sensor { origin: [1.1, 0.0], pitch: [0.4, 0.4], width: 7, height: 3, ..s };
        let g = off.shadow_grid((0.0, 1.0), shadow_z, 0.0, 1).unwrap();
        assert!((g.origin[0] + 0.14).abs() < 1e-12 && g.width == 7, "{g:?}");
        // Facing the range view (θ = 0), the shadow view is the range view's columns: the
        // largest image has the largest shadow view.
        let widest = Sensor { origin: [0.0, 0.0], pitch: [0.5, 0.5], ..Sensor::square(MAX_IMAGE_SIDE, 1.0, 0.0) };
        assert_eq!(widest.shadow_grid((0.0, 1.0), shadow_z, 0.0, 1).unwrap().width, MAX_IMAGE_SIDE);
        // Too deep for 16384 columns, or a depth range that overflowed: refused.
        for z_range in [(0.0, 1e5), (0.0, f64::INFINITY)] {
            let e = s.shadow_grid(z_range, shadow_z, 0.0, 1).unwrap_err().to_string();
            assert!(e.contains("columns"), "{e}");
        }
    }

    #[test]
    fn a_local_origin_is_the_grids_centre_on_a_lattice_of_its_extent() {
        // Centre (1001.5, 1999.5, 11), extent 4 (the width): the multiples of 4 nearest.
        let far = ViewGrid { origin: [1000.0, 2000.0], pitch: [1.0, 1.0], width: 4, height: 2, z_range: (10.0, 12.0) };
        assert_eq!(far.local_origin(), DVec3::new(1000.0, 2000.0, 12.0));
        // A grid about the frame's origin keeps it.
        assert_eq!(grid().local_origin(), DVec3::ZERO);
        // Two rows of pitch 1 from y = 9.7: the centre's y, 9.2, is 4.6 steps of 2 (the
        // extent), nearer 10 than 8.
        let rows = ViewGrid { origin: [0.0, 9.7], pitch: [1.0, 1.0], width: 1, height: 2, z_range: (0.0, 1.0) };
        assert_eq!(rows.local_origin(), DVec3::new(0.0, 10.0, 0.0));
        // A pixel 20 deep: the depth is the extent (step 32), and the centre (5, 7, 20) is
        // nearest (0, 0, 32).
        let deep = ViewGrid { origin: [5.0, 7.0], pitch: [1.0, 1.0], width: 1, height: 1, z_range: (10.0, 30.0) };
        assert_eq!(deep.local_origin(), DVec3::new(0.0, 0.0, 32.0));
    }

    #[test]
    fn a_spheres_reach_counts_pixels_along_the_farther_axis() {
        // Centre (2, −1), radius 0.35, pitch 0.1: 23.5 columns, 13.5 rows from pixel (0, 0).
        assert!((grid().reach(DVec3::new(2.0, -1.0, 0.0), 0.35) - 23.5).abs() < 1e-9);
        assert!((grid().reach(DVec3::new(1.0, -3.0, 0.0), 0.35) - 33.5).abs() < 1e-9);
        // From a first pixel at (1, 2): 11.5 columns or 43.5 rows.
        let moved = ViewGrid { origin: [1.0, 2.0], ..grid() };
        assert!((moved.reach(DVec3::new(2.0, -2.0, 0.0), 0.35) - 43.5).abs() < 1e-9);
        assert!((moved.reach(DVec3::new(5.0, 1.0, 0.0), 0.35) - 43.5).abs() < 1e-9);
        assert!((moved.reach(DVec3::new(4.0, 1.5, 0.0), 0.35) - 33.5).abs() < 1e-9);
    }

    #[test]
    fn a_footprint_is_measured_from_the_grids_first_pixel() {
        // The first pixel at (1, 2): centre (3, 1) is pixel (20, 10), as (2, −1) is from (0, 0).
        let moved = ViewGrid { origin: [1.0, 2.0], ..grid() };
        let r = moved.footprint(DVec3::new(3.0, 1.0, 0.0), 0.35, 1).unwrap();
        assert_eq!(r, PixelRect { col: 15, row: 5, width: 11, height: 11 });
    }

    proptest::proptest! {
        /// Wherever a grid lies, its local origin is a multiple of the power of two at least
        /// its extent, within half of it of the grid's centre on every axis.
        #[test]
        fn a_local_origin_lies_on_its_lattice_beside_the_centre(
            x0 in -1e4f64..1e4, y0 in -1e4f64..1e4, z0 in -1e4f64..1e4,
            dx in 1e-3f64..1.0, dy in 1e-3f64..1.0, depth in 1e-3f64..10.0,
            width in 1u32..2000, height in 1u32..2000,
        ) {
            let g = ViewGrid { origin: [x0, y0], pitch: [dx, dy], width, height, z_range: (z0, z0 + depth) };
            let (w, h) = (f64::from(width), f64::from(height));
            let centre = DVec3::new(x0 + (w - 1.0) / 2.0 * dx, y0 - (h - 1.0) / 2.0 * dy, z0 + depth / 2.0);
            let step = (w * dx).max(h * dy).max(depth).log2().ceil().exp2();
            let local = g.local_origin();
            for axis in 0..3 {
                proptest::prop_assert_eq!((local[axis] / step).fract(), 0.0);
                proptest::prop_assert!((local[axis] - centre[axis]).abs() <= step / 2.0 + 1e-9 * step);
            }
        }
    }

    #[test]
    fn depth_bounds_widen_the_spheres_extent_by_its_hundredth_and_a_millionth() {
        // Depths 1 to 5.5: a margin of 0.045 and 6.5e-6.
        let (lo, hi) = depth_bounds([(DVec3::new(0.0, 0.0, 2.0), 1.0), (DVec3::new(3.0, 0.0, 5.0), 0.5)]);
        let margin = 0.045 + 1e-6 * 6.5;
        assert!((lo - 1.0 + margin).abs() < 1e-12 && (hi - 5.5 - margin).abs() < 1e-12, "({lo}, {hi})");
        // A point: the absolute margin alone.
        let (lo, hi) = depth_bounds([(DVec3::new(0.0, 0.0, 5.0), 0.0)]);
        assert!((lo - 5.0 + 6e-6).abs() < 1e-12 && (hi - 5.0 - 6e-6).abs() < 1e-12, "({lo}, {hi})");
        assert_eq!(depth_bounds([]), (-1.0, 1.0));
    }

    #[test]
    fn a_footprint_covers_the_sphere_with_its_margin() {
        // Centre (2, −1) is pixel (20, 10); radius 0.35 spans 3.5 pixels each way.
        let r = grid().footprint(DVec3::new(2.0, -1.0, 0.0), 0.35, 1).unwrap();
        assert_eq!(r, PixelRect { col: 15, row: 5, width: 11, height: 11 });
    }

    #[test]
    fn a_footprint_is_clipped_to_the_grid_or_absent() {
        let r = grid().footprint(DVec3::new(-0.05, 0.0, 0.0), 0.2, 1).unwrap();
        assert_eq!((r.col, r.row), (0, 0));
        assert_eq!(grid().footprint(DVec3::new(50.0, 0.0, 0.0), 1.0, 1), None);
        assert_eq!(grid().footprint(DVec3::new(5.0, 3.0, 0.0), 1.0, 1), None);
    }
}
