//! The attachments of one view: label (R32_UINT), linear z (R32_SFLOAT), a depth buffer
//! that resolves visibility, and for the shadow view the depth slope per column.

use super::pipelines::{LABEL_FORMAT, VALUE_FORMAT};
use crate::error::Result;
use crate::gpu::{Access, GpuContext, Image, ImageDesc, ImageTransition};
use ash::vk;
use std::sync::Arc;

pub struct ViewTargets {
    pub label: Image,
    pub z: Image,
    pub slope: Option<Image>,
    pub depth: Image,
}

impl ViewTargets {
    pub fn new(ctx: &Arc<GpuContext>, width: u32, height: u32, with_slope: bool, name: &str) -> Result<Self> {
        let extent = vk::Extent2D { width, height };
        Ok(Self {
            label: Image::new(ctx, ImageDesc::attachment(LABEL_FORMAT, extent), &format!("{name} label"))?,
            z: Image::new(ctx, ImageDesc::attachment(VALUE_FORMAT, extent), &format!("{name} z"))?,
            slope: match with_slope {
                true => Some(Image::new(ctx, ImageDesc::attachment(VALUE_FORMAT, extent), &format!("{name} slope"))?),
                false => None,
            },
            depth: Image::new(ctx, ImageDesc::depth(extent), &format!("{name} depth"))?,
        })
    }

    /// Transitions of the colour attachments (label, z, slope) from one use to another.
    pub fn colour_transitions(&self, from: Access, to: Access) -> Vec<ImageTransition<'_>> {
        [Some(&self.label), Some(&self.z), self.slope.as_ref()]
            .into_iter()
            .flatten()
            .map(|image| ImageTransition { image, from, to })
            .collect()
    }

    /// Transitions that make every attachment ready to be rendered into.
    pub fn prepare_for_rendering(&self) -> Vec<ImageTransition<'_>> {
        let mut t = self.colour_transitions(Access::Nothing, Access::ColorAttachmentWrite);
        t.push(ImageTransition { image: &self.depth, from: Access::Nothing, to: Access::DepthAttachmentWrite });
        t
    }
}
