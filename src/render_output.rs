//! What a render returns: the range image (a 3D point per valid pixel), the labels before
//! and after shadowing and the effects, why each pixel without a point has none, and the time
//! each pass took on the GPU. Plain data, apart from the
//! renderer, so that writing it (io/) does not depend on rendering.

use crate::effects::{Effects, Reason};
use crate::raster_choice::Raster;
use crate::sensor::{Sensor, View};
use crate::shadow::ShadowSettings;

#[derive(Debug, Clone)]
#[non_exhaustive]
pub struct RenderOutput {
    pub sensor: Sensor,
    pub shadow: ShadowSettings,
    pub effects: Effects,
    /// Whether the image was shadowed: a shadow pass ran (not with mode `none` or θ = 0), or
    /// mode `exact` cast the shadow rays.
    pub shadow_pass: bool,
    /// The rasterizer that rendered the views; `None` where rays were cast on the CPU alone (a
    /// rig other than the paper's scanner).
    pub raster: Option<Raster>,
    /// Row-major labels after shadowing and the effects; 0 = no data.
    pub label: Vec<u32>,
    /// Row-major labels of the range view alone.
    pub label_unshadowed: Vec<u32>,
    /// Row-major depth of the nearest surface as measured, noise and quantization included
    /// (meaningful where `label_unshadowed` ≠ 0): the range frame's z of an orthographic view,
    /// Z along the optical axis of a pinhole one.
    pub z: Vec<f32>,
    /// Row-major: why the pixel has no point ([`Reason::Valid`] where it has one).
    pub reason: Vec<Reason>,
    /// Row-major: bit k set where witness k (the sensor's, in file order) does not see the
    /// point; 0 on valid pixels and where no surface was hit.
    pub witness: Vec<u32>,
    /// The passes recorded, in order, with their GPU times; in mode `exact` and under a rig
    /// cast on the CPU, first the CPU's ray casting, timed on the wall clock.
    pub timings: Vec<PassTime>,
}

/// One recorded pass and its time in milliseconds: on the GPU (`None` on a device without
/// timestamps), or for exact mode's rays on the CPU's wall clock. Names: `range`, `shadow`,
/// `shadow mask` (a rig's pinhole views: `range`, its witnesses drawn too, and `shadow mask`,
/// their label test), `exact rays` (CPU), `cast upload` (a cast image, for the effects), and
/// each effect's
/// [`Effect::pass_name`](crate::effects::Effect::pass_name).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PassTime {
    pub name: &'static str,
    pub ms: Option<f64>,
    /// Timed on the CPU (exact mode's ray casting), not on the GPU.
    pub on_cpu: bool,
}

impl RenderOutput {
    pub fn width(&self) -> u32 {
        self.sensor.width()
    }

    pub fn height(&self) -> u32 {
        self.sensor.height()
    }

    /// The measured 3D point of pixel `index` (row-major), or `None` where there is no data
    /// (background or shadow): on the pixel's ray at its depth (`View::point`).
    pub fn point(&self, index: usize) -> Option<[f32; 3]> {
        if self.label[index] == 0 {
            return None;
        }
        let w = self.width() as usize;
        // z as measured in f32; x, y where the pixel's ray reaches that depth (an orthographic
        // view's pixel centre).
        let p = self.sensor.reference.point((index % w) as u32, (index / w) as u32, f64::from(self.z[index]));
        Some([p.x as f32, p.y as f32, self.z[index]])
    }

    /// Heights toward the sensor (larger is closer) and the model units a pixel spans, as the
    /// range preview shades them (src/io/preview.rs): an orthographic view's z and pitch; a
    /// pinhole view's −Z, and a pixel's width at the median depth of its valid pixels.
    pub fn relief(&self) -> (Vec<f32>, [f64; 2]) {
        match self.sensor.reference {
            View::Orthographic(o) => (self.z.clone(), o.pitch),
            View::Pinhole(p) => {
                let mut depths: Vec<f32> = self.z.iter().zip(&self.label).filter(|p| *p.1 != 0).map(|p| *p.0).collect();
                let middle = depths.len() / 2;
                let median = match depths.is_empty() {
                    true => 1.0,
                    false => f64::from(*depths.select_nth_unstable_by(middle, f32::total_cmp).1),
                };
                let k = p.intrinsics;
                (self.z.iter().map(|z| -z).collect(), [median / k.fx, median / k.fy])
            }
        }
    }

    /// Pixels each witness (in file order) did not see.
    pub fn pixels_lost_by_witness(&self) -> Vec<usize> {
        (0..self.sensor.witnesses.len())
            .map(|k| self.witness.iter().filter(|&&bits| bits >> k & 1 == 1).count())
            .collect()
    }

    /// Pixels with data before shadowing but not after.
    pub fn shadowed_pixels(&self) -> usize {
        self.pixels_lost_to(Reason::Shadow)
    }

    /// Pixels without a point for this reason.
    pub fn pixels_lost_to(&self, reason: Reason) -> usize {
        self.reason.iter().filter(|&&r| r == reason).count()
    }
}
