//! The attachments of one view: its colour attachments, in the fragment shader's output
//! order (shaders/raster.frag), and a depth buffer that resolves visibility.
//!
//! - Range view: label, z, ∂z/∂x, ∂z/∂y — the surface, its point and its plane's gradient,
//!   which the depth-mode shadow test needs to know which way the surface faces.
//! - Shadow view: one RGBA32UI attachment holding label, draw index and triangle — a
//!   visibility buffer: which triangle of which draw is nearest, so the depth-mode test can
//!   intersect the camera ray with it exactly. One attachment, so the mask reads a pixel's
//!   three words with one image load (it reads nine pixels per point).

use super::pipelines::{LABEL_FORMAT, VALUE_FORMAT, VISIBILITY_FORMAT};
use crate::error::Result;
use crate::gpu::{GpuContext, Image, ImageDesc};
use ash::vk;
use std::sync::Arc;

/// Which of the two views; fixes its colour attachments.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ViewKind {
    Range,
    Shadow,
}

impl ViewKind {
    /// (format, name, bytes a pixel) of each colour attachment, at fragment output locations
    /// 0, 1, …
    pub const fn colour_attachments(self) -> &'static [(vk::Format, &'static str, u64)] {
        match self {
            ViewKind::Range => &[
                (LABEL_FORMAT, "label", 4),
                (VALUE_FORMAT, "z", 4),
                (VALUE_FORMAT, "dz/dx", 4),
                (VALUE_FORMAT, "dz/dy", 4),
            ],
            ViewKind::Shadow => &[(VISIBILITY_FORMAT, "visibility (label, draw index, triangle)", 16)],
        }
    }

    pub fn colour_formats(self) -> Vec<vk::Format> {
        self.colour_attachments().iter().map(|&(format, _, _)| format).collect()
    }

    /// Bytes a pixel of this view's attachments takes (colour and a 4-byte depth).
    pub fn bytes_per_pixel(self) -> u64 {
        self.colour_attachments().iter().map(|&(_, _, bytes)| bytes).sum::<u64>() + 4
    }
}

pub struct ViewTargets {
    /// In [`ViewKind::colour_attachments`] order.
    pub colour: Vec<Image>,
    pub depth: Image,
}

impl ViewTargets {
    pub fn new(ctx: &Arc<GpuContext>, kind: ViewKind, width: u32, height: u32, name: &str) -> Result<Self> {
        let extent = vk::Extent2D { width, height };
        let colour = kind
            .colour_attachments()
            .iter()
            .map(|&(format, what, _)| Image::new(ctx, ImageDesc::attachment(format, extent), &format!("{name} {what}")))
            .collect::<Result<_>>()?;
        Ok(Self { colour, depth: Image::new(ctx, ImageDesc::depth(extent), &format!("{name} depth"))? })
    }

    /// The range view's label.
    pub fn label(&self) -> &Image {
        &self.colour[0]
    }

    /// The range view's z.
    pub fn z(&self) -> &Image {
        &self.colour[1]
    }
}
