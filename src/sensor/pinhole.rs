//! Pinhole views: a camera or projector with intrinsics K, in the OpenCV / BOP convention that
//! datasets store (docs/sensors-and-rigs.md). Pixel (col c, row r) has its centre at image
//! coordinates (u, v) = (c, r); the view's frame has x right, y down, z forward, and a point
//! (X, Y, Z) projects to u = fx·X/Z + cx, v = fy·Y/Z + cy. The image covers
//! [−½, width − ½) × [−½, height − ½): each pixel's square around its centre.

use super::orthographic::MAX_IMAGE_SIDE;
use crate::error::{Error, Result};
use glam::{DVec2, DVec3};

/// A pinhole view's image size and intrinsics (pixels).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Intrinsics {
    pub width: u32,
    pub height: u32,
    pub fx: f64,
    pub fy: f64,
    pub cx: f64,
    pub cy: f64,
}

/// A pinhole reference view (`[sensor] kind = "pinhole"`): range is measured along its rays,
/// Z along its optical axis, between `near` and `far` (model units).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Pinhole {
    pub intrinsics: Intrinsics,
    pub near: f64,
    pub far: f64,
}

/// The focal lengths a view may have, in pixels (and the largest |cx|, |cy|).
pub const MIN_FOCAL: f64 = 1e-6;
pub const MAX_FOCAL: f64 = 1e9;

impl Intrinsics {
    /// Checks the size and intrinsics; `owner` (`[sensor]`, `[[sensor.witness]] 1 ("ir")`)
    /// starts the message of a refusal, which names the key.
    pub fn validate(&self, owner: &str) -> Result<()> {
        let bad = |m: String| Err(Error::Scene(format!("{owner}: {m}")));
        let (w, h) = (self.width, self.height);
        if w == 0 || h == 0 || w > MAX_IMAGE_SIDE || h > MAX_IMAGE_SIDE {
            return bad(format!("width = {w}, height = {h}: each side must lie between 1 and {MAX_IMAGE_SIDE} pixels"));
        }
        // The score pass reads 1/fx, 1/fy, cx and cy as f32 (src/verify/area.rs): bounds far
        // beyond any camera's keep them normal, finite f32s there.
        for (key, value) in [("fx", self.fx), ("fy", self.fy)] {
            if !(value.is_finite() && (MIN_FOCAL..=MAX_FOCAL).contains(&value)) {
                return bad(format!(
                    "{key} = {value} must be a focal length in pixels between {MIN_FOCAL:e} and {MAX_FOCAL:e}"
                ));
            }
        }
        for (key, value) in [("cx", self.cx), ("cy", self.cy)] {
            if !(value.is_finite() && value.abs() <= MAX_FOCAL) {
                return bad(format!("{key} = {value} must be finite, within ±{MAX_FOCAL:e} pixels"));
            }
        }
        Ok(())
    }

    /// The direction of the ray through the centre of pixel (col, row), scaled so that its z
    /// is 1: the point at depth Z along it is `Z · ray`.
    pub fn ray(&self, col: u32, row: u32) -> DVec3 {
        DVec3::new((f64::from(col) - self.cx) / self.fx, (f64::from(row) - self.cy) / self.fy, 1.0)
    }

    /// Image coordinates (u, v) of a point in this view's frame; `None` for a point on or
    /// behind the plane of its centre (Z ≤ 0), which it cannot see.
    pub fn project(&self, p: DVec3) -> Option<DVec2> {
        (p.z > 0.0).then(|| DVec2::new(self.fx * p.x / p.z + self.cx, self.fy * p.y / p.z + self.cy))
    }

    /// Whether image coordinates fall on the image (a pixel's square around its centre).
    pub fn contains(&self, uv: DVec2) -> bool {
        (-0.5..f64::from(self.width) - 0.5).contains(&uv.x) && (-0.5..f64::from(self.height) - 0.5).contains(&uv.y)
    }

    /// The directions (z = 1) of the image's four outer corners, which span every ray it sees.
    pub fn corner_rays(&self) -> [DVec3; 4] {
        let (u0, v0, u1, v1) = (-0.5, -0.5, f64::from(self.width) - 0.5, f64::from(self.height) - 0.5);
        [(u0, v0), (u1, v0), (u1, v1), (u0, v1)]
            .map(|(u, v)| DVec3::new((u - self.cx) / self.fx, (v - self.cy) / self.fy, 1.0))
    }
}

impl Pinhole {
    pub fn validate(&self) -> Result<()> {
        self.intrinsics.validate("[sensor]")?;
        if !(self.near.is_finite() && self.near >= 0.0) {
            return Err(Error::Scene(format!("[sensor]: near = {} must be finite and at least 0", self.near)));
        }
        if self.far.partial_cmp(&self.near) != Some(std::cmp::Ordering::Greater) {
            return Err(Error::Scene(format!(
                "[sensor]: far = {} must lie beyond near = {} (leave it out for no far limit)",
                self.far, self.near
            )));
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn kinect() -> Intrinsics {
        Intrinsics { width: 640, height: 480, fx: 500.0, fy: 400.0, cx: 319.5, cy: 239.5 }
    }

    /// A point on pixel (c, r)'s ray at any depth projects back onto (c, r); the convention's
    /// centre pixel looks along the axis.
    #[test]
    fn a_pixels_ray_projects_back_onto_its_centre() {
        let k = kinect();
        for (col, row, depth) in [(0, 0, 1.0), (639, 479, 2.5), (100, 300, 0.3)] {
            let uv = k.project(depth * k.ray(col, row)).unwrap();
            assert!((uv - DVec2::new(f64::from(col), f64::from(row))).length() < 1e-9, "{uv}");
        }
        let centred = Intrinsics { cx: 320.0, cy: 240.0, ..k };
        assert_eq!(centred.ray(320, 240), DVec3::Z);
        assert_eq!(k.project(DVec3::new(0.0, 0.0, -1.0)), None);
        assert_eq!(k.project(DVec3::new(1.0, 0.0, 0.0)), None);
    }

    /// The image is the pixels' squares: from −½ to 639½ across, −½ to 479½ down.
    #[test]
    fn the_image_covers_each_pixels_square() {
        let k = kinect();
        for (u, v, inside) in [(-0.5, -0.5, true), (-0.51, 0.0, false), (639.49, 479.49, true), (639.5, 0.0, false)] {
            assert_eq!(k.contains(DVec2::new(u, v)), inside, "({u}, {v})");
        }
        let [top_left, .., bottom_left] = k.corner_rays();
        assert_eq!(top_left, DVec3::new(-320.0 / 500.0, -240.0 / 400.0, 1.0));
        assert_eq!(bottom_left, DVec3::new(-320.0 / 500.0, 240.0 / 400.0, 1.0));
    }

    #[test]
    fn bad_intrinsics_are_refused_by_key() {
        let k = kinect();
        for (bad, key) in [
            (Intrinsics { fx: 0.0, ..k }, "fx = 0"),
            (Intrinsics { fy: -1.0, ..k }, "fy = -1"),
            (Intrinsics { fx: f64::NAN, ..k }, "fx = NaN"),
            (Intrinsics { cx: f64::INFINITY, ..k }, "cx = inf"),
            // Beyond the score pass's f32: 1/fx would be subnormal, cy not a float.
            (Intrinsics { fx: 1e10, ..k }, "fx = 10000000000"),
            (Intrinsics { fy: 1e-9, ..k }, "fy = 0.000000001"),
            (Intrinsics { cy: 2e9, ..k }, "cy = 2000000000"),
            (Intrinsics { width: 0, ..k }, "width = 0"),
            (Intrinsics { height: MAX_IMAGE_SIDE + 1, ..k }, "width = 640, height = 16385"),
        ] {
            let e = bad.validate("[sensor]").unwrap_err().to_string();
            assert!(e.contains(&format!("[sensor]: {key}")), "{e}");
        }
        let view = Pinhole { intrinsics: k, near: 0.0, far: f64::INFINITY };
        assert!(view.validate().is_ok());
        for (bad, key) in [
            (Pinhole { near: -1.0, ..view }, "near = -1"),
            (Pinhole { near: 2.0, far: 2.0, ..view }, "far = 2"),
            (Pinhole { far: f64::NAN, ..view }, "far = NaN"),
        ] {
            let e = bad.validate().unwrap_err().to_string();
            assert!(e.contains(key), "{e}");
        }
    }
}
