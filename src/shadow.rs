//! How a range pixel is decided to be in triangulation shadow (DESIGN.md "The shadow test").
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
//!      triangle neighbours, `Mesh::triangle_neighbours`) from the triangle the pixel saw to
//!      the one over p', stopping where the surface ends or folds away (a silhouette), and
//!      compares that triangle's plane at p' with p'.z. Triangles much smaller than a pixel,
//!      missing from the buffer, are found this way.
//!
//!   Exact, up to the bias, wherever the occluder over p' is seen at one of those nine pixel
//!   centres or joined by edges to a triangle that is: only an occluder thinner than a pixel
//!   and seen nowhere near p' escapes. The bias is [`DEPTH_BIAS_PIXELS`] of a pixel pitch plus
//!   f32 rounding ([`DEPTH_BIAS_RELATIVE`] of the coordinates, scaled by how steep the planes
//!   are). A walk is at most 32 steps; one that gives up falls back on the seen triangle's
//!   plane, extrapolated to p', with an allowance for the creases in between.
//! - `none`: no shadow pass at all.

use serde::{Deserialize, Serialize};

#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum ShadowMode {
    None,
    #[default]
    Label,
    Depth,
}

/// The scene file's `[shadow]` table.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ShadowSettings {
    #[serde(default)]
    pub mode: ShadowMode,
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
        }
    }

    /// Whether a shadow pass runs at all: not in mode `none`, and not at θ = 0, where the
    /// camera looks along the projector and nothing can be in shadow.
    pub fn needs_shadow_pass(self, theta_deg: f64) -> bool {
        self != ShadowMode::None && theta_deg != 0.0
    }

    /// The code the shadow-mask shader switches on.
    pub(crate) fn shader_code(self) -> u32 {
        match self {
            ShadowMode::None => 0,
            ShadowMode::Label => 1,
            ShadowMode::Depth => 2,
        }
    }
}
