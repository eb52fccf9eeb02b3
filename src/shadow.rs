//! How a range pixel is decided to be in triangulation shadow (DESIGN.md "The shadow test").
//!
//! - `label`: the paper's Fig. 4. The pixel's point p is moved into the shadow frame,
//!   p' = R_y(−θ)·p, and the label at the nearest shadow-buffer pixel is compared with the
//!   pixel's own; a difference means shadow. It leaves a rim of false "missing" pixels along
//!   surface edges and cannot see a curved surface shadow itself (the paper says so).
//! - `depth`: the shadow buffer's depth at that pixel is compared with p'.z. The buffer holds
//!   the nearest surface's depth at the shadow pixel's centre, up to half a pixel from p';
//!   over that offset a visible surface's depth changes by at most |∂z'/∂col| · offset, so
//!   the bias is that slope (the larger of the hit shadow pixel's and its neighbour's toward
//!   p', from the rasterizer's derivative) times the offset, plus [`DEPTH_BIAS_PIXELS`] of a
//!   pixel pitch and a few f32 ulps of the depth. Catches self-shadowing within one surface.
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
