//! How a range pixel is decided to be in triangulation shadow (docs/design.md "The shadow test").
//!
//! - `label`: the paper's Fig. 4. The pixel's point p is moved into the shadow frame,
//!   p' = R_y(−θ)·p, and the label at the nearest shadow-buffer pixel is compared with the
//!   pixel's own; a difference means shadow. It leaves a rim of false "missing" pixels along
//!   surface edges and cannot see a curved surface shadow itself (the paper says so).
//! - `depth`: exact ray casting from the point toward the camera, as far as the two views can
//!   tell. The point is in shadow when
//!   1. the side of its surface that the projector lights turns away from the camera,
//!      n · d_cam ≤ 0 with n = (−∂z/∂x, −∂z/∂y, 1) from the range view's plane gradient (a
//!      surface seen from behind, or exactly edge-on, is not measured, however thin), or
//!   2. a surface lies above p' on the camera ray through it. The shadow view is a visibility
//!      buffer (which triangle of which draw is nearest at each pixel); for each surface seen
//!      at the 3×3 shadow pixels around p', the test walks over that surface's edges (its
//!      edge links, `Mesh::edge_links`) from the triangle the pixel saw to
//!      the one over p', stopping where the surface ends or folds away (a silhouette), and
//!      compares that triangle's plane at p' with p'.z. Triangles much smaller than a pixel,
//!      missing from the buffer, are found this way.
//!
//!   Exact, up to the bias, wherever the occluder over p' is seen at one of those nine pixel
//!   centres or joined by edges to a triangle that is: only an occluder thinner than a pixel
//!   and seen nowhere near p' escapes. The bias is [`DEPTH_BIAS_PIXELS`] of a pixel pitch plus
//!   f32 rounding ([`DEPTH_BIAS_RELATIVE`] of the coordinates, scaled by how steep the planes
//!   are), and a plane is evaluated up to the walk's f32 tolerance beyond its triangle. A walk
//!   is at most 256 steps (a dense sphere's pole takes up to half its segments); one that gives
//!   up has wandered off the layer over p' (across a silhouette f32 misjudged) and says
//!   nothing of it. Under a rig the same walk runs toward each witness (src/render/pinhole/).
//! - `exact`: two rays in f64 on the CPU at every pixel centre (src/exact/): the first hit
//!   along −z, then a ray from it toward the camera. The product's own ground truth, and the
//!   slow end of `rangesynth accuracy`'s curve; its images go through the same effect and
//!   score passes as the GPU modes'.
//! - `none`: no shadow pass at all.
//!
//! Two knobs refine the GPU modes: `columns = k` renders the shadow view with k columns per
//! range pitch (its rows already coincide with the range rows), and `neighbourhood = "2x2"`
//! makes the label test keep a pixel whose label is seen at any of the four shadow pixels
//! around p' (the paper's test reads only the nearest).

use crate::error::{Error, Result};
use serde::{Deserialize, Serialize};

#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
#[non_exhaustive]
pub enum ShadowMode {
    None,
    #[default]
    Label,
    Depth,
    Exact,
}

/// Which shadow pixels the label test reads.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
pub enum Neighbourhood {
    /// The nearest (the paper's Fig. 4).
    #[default]
    #[serde(rename = "nearest")]
    Nearest,
    /// The four whose centres surround p': lit if any of them carries the pixel's label.
    #[serde(rename = "2x2")]
    Square2,
}

/// The scene file's `[shadow]` table.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ShadowSettings {
    #[serde(default)]
    pub mode: ShadowMode,
    /// Shadow-view columns per range-view column (1 to [`MAX_SHADOW_COLUMNS`]).
    #[serde(default = "one", skip_serializing_if = "is_one")]
    pub columns: u32,
    /// The label test's shadow pixels (mode `label` only).
    #[serde(default, skip_serializing_if = "is_nearest")]
    pub neighbourhood: Neighbourhood,
}

/// Most shadow-view columns per range-view column.
pub const MAX_SHADOW_COLUMNS: u32 = 8;

fn one() -> u32 {
    1
}

fn is_one(k: &u32) -> bool {
    *k == 1
}

fn is_nearest(n: &Neighbourhood) -> bool {
    *n == Neighbourhood::Nearest
}

impl Default for ShadowSettings {
    fn default() -> Self {
        Self::of(ShadowMode::default())
    }
}

impl ShadowSettings {
    /// `mode` with one shadow column per range column and the nearest-pixel label test.
    pub fn of(mode: ShadowMode) -> Self {
        Self { mode, columns: 1, neighbourhood: Neighbourhood::Nearest }
    }

    pub fn validate(&self) -> Result<()> {
        if !(1..=MAX_SHADOW_COLUMNS).contains(&self.columns) {
            return Err(Error::Scene(format!(
                "[shadow] columns = {} must lie between 1 and {MAX_SHADOW_COLUMNS}",
                self.columns
            )));
        }
        if self.neighbourhood != Neighbourhood::Nearest && self.mode != ShadowMode::Label {
            return Err(Error::Scene(format!(
                "[shadow] neighbourhood = \"2x2\" refines the label test; mode \"{}\" does not read labels",
                self.mode.as_str()
            )));
        }
        Ok(())
    }

    /// The test the shadow mask runs, where a shadow pass runs (modes `label` and `depth`).
    pub(crate) fn test(&self) -> Option<ShadowTest> {
        match (self.mode, self.neighbourhood) {
            (ShadowMode::Label, Neighbourhood::Nearest) => Some(ShadowTest::Label),
            (ShadowMode::Label, Neighbourhood::Square2) => Some(ShadowTest::LabelSquare),
            (ShadowMode::Depth, _) => Some(ShadowTest::Depth),
            (ShadowMode::None | ShadowMode::Exact, _) => None,
        }
    }
}

/// The tests of shaders/stages/shadow_mask.comp. Each has a pipeline of its own, the test a
/// specialization constant, so that a software rasterizer, which runs both sides of a branch
/// on a uniform value, runs only its test's code (src/render/stages/shadow_mask.rs).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[repr(u32)]
pub(crate) enum ShadowTest {
    /// The paper's: the shadow pixel nearest p' carries the pixel's label.
    Label = 1,
    /// Any of the four shadow pixels around p' carries it.
    LabelSquare = 2,
    /// Nothing seen near p' in the shadow view rises above it.
    Depth = 3,
}

/// Constant part of the depth test's bias, as a fraction of the pixel pitch dx.
pub const DEPTH_BIAS_PIXELS: f64 = 1e-3;
/// f32 rounding allowance of the depth test, relative to the largest |coordinate| involved.
pub const DEPTH_BIAS_RELATIVE: f64 = 8.0 * f32::EPSILON as f64;

impl ShadowMode {
    pub fn as_str(self) -> &'static str {
        match self {
            ShadowMode::None => "none",
            ShadowMode::Label => "label",
            ShadowMode::Depth => "depth",
            ShadowMode::Exact => "exact",
        }
    }

    /// Whether the GPU renders a shadow view: in modes `label` and `depth`, and not at θ = 0,
    /// where the camera looks along the projector and nothing can be in shadow.
    pub fn needs_shadow_pass(self, theta_deg: f64) -> bool {
        matches!(self, ShadowMode::Label | ShadowMode::Depth) && theta_deg != 0.0
    }

    /// Whether images carry shadowed labels beside the unshadowed ones: a shadow pass ran, or
    /// the CPU cast the shadow rays.
    pub fn shadows(self, theta_deg: f64) -> bool {
        self == ShadowMode::Exact || self.needs_shadow_pass(theta_deg)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A shadow view is rendered in modes `label` and `depth` at θ ≠ 0 only; images carry
    /// shadows then, and in mode `exact` at any θ.
    #[test]
    fn which_modes_render_a_shadow_view_and_which_images_carry_shadows() {
        use ShadowMode::*;
        for (mode, theta, pass, shadows) in [
            (None, 45.0, false, false),
            (Label, 0.0, false, false),
            (Label, 45.0, true, true),
            (Depth, -30.0, true, true),
            (Depth, 0.0, false, false),
            (Exact, 45.0, false, true),
            (Exact, 0.0, false, true),
        ] {
            assert_eq!(mode.needs_shadow_pass(theta), pass, "{mode:?} at θ = {theta}");
            assert_eq!(mode.shadows(theta), shadows, "{mode:?} at θ = {theta}");
        }
    }

    /// The settings a header records (src/io/exr_file.rs) leave out only the defaults, and
    /// read back as they were.
    #[test]
    fn settings_written_leave_out_defaults_and_read_back_whole() {
        let paper = ShadowSettings::of(ShadowMode::Label);
        assert_eq!(toml::to_string(&paper).unwrap().trim(), "mode = \"label\"");
        let finest = ShadowSettings { columns: 2, neighbourhood: Neighbourhood::Square2, ..paper };
        let text = toml::to_string(&finest).unwrap();
        assert!(text.contains("columns = 2") && text.contains("neighbourhood = \"2x2\""), "{text}");
        for settings in [paper, finest] {
            let text = toml::to_string(&settings).unwrap();
            assert_eq!(toml::from_str::<ShadowSettings>(&text).unwrap(), settings, "{text}");
        }
    }
}
