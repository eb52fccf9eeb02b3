//! A range image as files hold it: a 3D point and a label per pixel, why a pixel holds none,
//! plus the sensor, shadow and effects settings it was made with, when known. `render` writes one; `verify` reads one as
//! the sensed image.

use crate::effects::Effects;
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
    /// Row-major [`Reason`](crate::effects::Reason) codes, where the file has them (older files have none).
    pub reason: Option<Vec<u32>>,
    /// Row-major witness bits (bit k: witness k did not see the point), where the file has
    /// them (older files have none).
    pub witness: Option<Vec<u32>>,
    pub sensor: Option<Sensor>,
    pub shadow: Option<ShadowSettings>,
    pub effects: Option<Effects>,
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
            reason: Some(out.reason.iter().map(|r| r.code()).collect()),
            witness: Some(out.witness.clone()),
            sensor: Some(out.sensor.clone()),
            shadow: Some(out.shadow),
            effects: Some(out.effects),
        }
    }
}
