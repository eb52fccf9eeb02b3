//! The attachments of one view: its colour attachments, in the fragment shader's output
//! order (shaders/raster/raster.frag), and a depth buffer that resolves visibility.
//!
//! - Range view: label, z, ∂z/∂x, ∂z/∂y — the surface, its point and its plane's gradient,
//!   which the depth-mode shadow test needs to know which way the surface faces.
//! - Shadow view: one RGBA32UI attachment holding label, draw index and triangle — a
//!   visibility buffer: which triangle of which draw is nearest, so the depth-mode test can
//!   intersect the camera ray with it exactly. One attachment, so the mask reads a pixel's
//!   three words with one image load (it reads nine pixels per point).

use crate::error::{Error, Result};
use crate::gpu::{GpuContext, Image, ImageDesc, DEPTH_FORMAT};
use ash::vk;
use std::sync::Arc;

pub const LABEL_FORMAT: vk::Format = vk::Format::R32_UINT;
pub const VALUE_FORMAT: vk::Format = vk::Format::R32_SFLOAT;
/// The shadow view's visibility buffer: label, draw index, triangle (and a spare word).
pub const VISIBILITY_FORMAT: vk::Format = vk::Format::R32G32B32A32_UINT;

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

/// The attachment formats are near-universal, but a device that lacks one gets a clear error
/// instead of a validation failure later.
pub(super) fn check_formats(ctx: &GpuContext) -> Result<()> {
    use vk::FormatFeatureFlags as F;
    let needs = [
        (LABEL_FORMAT, F::COLOR_ATTACHMENT | F::STORAGE_IMAGE, "R32_UINT colour attachment and storage image"),
        (VALUE_FORMAT, F::COLOR_ATTACHMENT | F::STORAGE_IMAGE, "R32_SFLOAT colour attachment and storage image"),
        (
            VISIBILITY_FORMAT,
            F::COLOR_ATTACHMENT | F::STORAGE_IMAGE,
            "R32G32B32A32_UINT colour attachment and storage image",
        ),
        (DEPTH_FORMAT, F::DEPTH_STENCIL_ATTACHMENT, "D32_SFLOAT depth attachment"),
    ];
    for (format, features, what) in needs {
        // SAFETY: valid physical device of a live instance.
        let props = unsafe { ctx.instance().get_physical_device_format_properties(ctx.physical_device, format) };
        if !props.optimal_tiling_features.contains(features) {
            return Err(Error::Unsupported(what.into()));
        }
    }
    Ok(())
}
