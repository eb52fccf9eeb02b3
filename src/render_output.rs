//! What a render returns: the range image (a 3D point per valid pixel), the labels before
//! and after shadowing and the effects, why each pixel without a point has none, and the time
//! each pass took on the GPU. Plain data, apart from the
//! renderer, so that writing it (io/) does not depend on rendering.

use crate::effects::{Effects, Reason};
use crate::sensor::Sensor;
use crate::shadow::ShadowSettings;

#[derive(Debug, Clone)]
pub struct RenderOutput {
    pub sensor: Sensor,
    pub shadow: ShadowSettings,
    pub effects: Effects,
    /// Whether the image was shadowed: a shadow pass ran (not with mode `none` or θ = 0), or
    /// mode `exact` cast the shadow rays.
    pub shadow_pass: bool,
    /// The rasterizer that rendered the views.
    pub raster: crate::raster_choice::Raster,
    /// Row-major labels after shadowing and the effects; 0 = no data.
    pub label: Vec<u32>,
    /// Row-major labels of the range view alone.
    pub label_unshadowed: Vec<u32>,
    /// Row-major range-frame z of the nearest surface as measured, noise and quantization
    /// included (meaningful where `label_unshadowed` ≠ 0).
    pub z: Vec<f32>,
    /// Row-major: why the pixel has no point ([`Reason::Valid`] where it has one).
    pub reason: Vec<Reason>,
    /// The passes recorded, in order, with their GPU times; in mode `exact`, first the CPU's
    /// ray casting, timed on the wall clock.
    pub timings: Vec<PassTime>,
}

/// One recorded pass and its time in milliseconds: on the GPU (`None` on a device without
/// timestamps), or for exact mode's rays on the CPU's wall clock. Names: `range`, `shadow`,
/// `shadow mask`, `exact rays` (CPU), `exact upload`, and each effect's
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
        self.sensor.width
    }

    pub fn height(&self) -> u32 {
        self.sensor.height
    }

    /// The measured 3D point of pixel `index` (row-major), or `None` where there is no data
    /// (background or shadow). x, y are the pixel centre (orthographic sensor).
    pub fn point(&self, index: usize) -> Option<[f32; 3]> {
        if self.label[index] == 0 {
            return None;
        }
        let w = self.sensor.width as usize;
        let (x, y) = self.sensor.pixel_centre((index % w) as u32, (index / w) as u32);
        Some([x as f32, y as f32, self.z[index]])
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
