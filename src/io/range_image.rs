//! A range image as files hold it: a 3D point and a label per pixel, plus the sensor and
//! shadow settings it was made with, when known. `render` writes one; `verify` reads one as
//! the sensed image.

use crate::render_output::RenderOutput;
use crate::sensor::Sensor;
use crate::shadow::ShadowSettings;

#[derive(Debug, Clone, PartialEq)]
pub struct RangeImage {
    pub width: u32,
    pub height: u32,
    /// Row-major coordinates, NaN where `label` is 0.
    pub x: Vec<f32>,
    pub y: Vec<f32>,
    pub z: Vec<f32>,
    /// Row-major labels (segments), 0 = no data.
    pub label: Vec<u32>,
    pub sensor: Option<Sensor>,
    pub shadow: Option<ShadowSettings>,
}

impl From<&RenderOutput> for RangeImage {
    fn from(out: &RenderOutput) -> Self {
        let n = out.label.len();
        let (mut x, mut y, mut z) = (vec![f32::NAN; n], vec![f32::NAN; n], vec![f32::NAN; n]);
        for i in 0..n {
            if let Some([px, py, pz]) = out.point(i) {
                (x[i], y[i], z[i]) = (px, py, pz);
            }
        }
        Self {
            width: out.width(),
            height: out.height(),
            x,
            y,
            z,
            label: out.label.clone(),
            sensor: Some(out.sensor),
            shadow: Some(out.shadow),
        }
    }
}
