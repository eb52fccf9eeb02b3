//! An orthographic reference view: the paper's range image, looking down −z, pixel (col c,
//! row r) centred at `x = x0 + c·dx`, `y = y0 − r·dy` (docs/sensors-and-rigs.md).

use crate::error::{Error, Result};

/// Largest image side accepted before asking the device (lavapipe allows 16384).
pub const MAX_IMAGE_SIDE: u32 = 16384;

/// An orthographic view's pixel grid: `[sensor] kind = "orthographic"`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Orthographic {
    pub width: u32,
    pub height: u32,
    /// dx, dy: model units per pixel.
    pub pitch: [f64; 2],
    /// x, y of the centre of pixel (col 0, row 0).
    pub origin: [f64; 2],
}

impl Orthographic {
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

    /// Centre of pixel (col, row) in the range frame's x, y.
    pub fn pixel_centre(&self, col: u32, row: u32) -> (f64, f64) {
        (self.origin[0] + f64::from(col) * self.pitch[0], self.origin[1] - f64::from(row) * self.pitch[1])
    }
}
