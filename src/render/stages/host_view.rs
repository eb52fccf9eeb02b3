//! The range view of shadow mode `exact`, cast on the CPU (src/exact/) and copied into the
//! range view's attachments and the shadowed labels, where the raster, shadow and mask passes
//! would have written them: the effect passes and the sink then read it as they read a
//! rasterized view, so exact mode's images go through the same effects and the same score pass.

use crate::error::Result;
use crate::exact::ExactImage;
use crate::gpu::{Access, Buffer, GpuContext, Step};
use crate::render::targets::{ViewKind, ViewTargets};
use ash::vk;
use std::sync::Arc;

/// One exact image in host-visible memory: planes of one word a pixel, in the range view's
/// attachment order (label, z, ∂z/∂x, ∂z/∂y), then the shadowed labels.
pub(crate) struct HostView {
    planes: Buffer,
    size: (u32, u32),
}

/// Largest |∂z/∂x|, |∂z/∂y| uploaded: a plane seen almost edge-on keeps a finite f32 gradient.
const MAX_GRADIENT: f64 = 1e30;

impl HostView {
    /// Planes 0..4 are the attachments; plane 4 the shadowed labels.
    const PLANES: usize = ViewKind::Range.colour_attachments().len() + 1;
    /// Bytes a pixel takes (a word per plane).
    pub const BYTES_PER_PIXEL: u64 = 4 * Self::PLANES as u64;

    /// z is stored as the range view stores it: an f32 offset from `z_origin` where a surface
    /// was hit, 0.0 elsewhere (draw.rs).
    pub fn new(ctx: &Arc<GpuContext>, image: &ExactImage, z_origin: f64, name: &str) -> Result<Self> {
        let pixels = image.label.len();
        let mut words: Vec<u32> = Vec::with_capacity(Self::PLANES * pixels);
        words.extend(&image.label);
        let hit = |i: usize| image.label[i] != 0;
        words.extend((0..pixels).map(|i| if hit(i) { (image.z[i] - z_origin) as f32 } else { 0.0 }.to_bits()));
        for axis in 0..2 {
            words.extend(image.gradient.iter().map(|g| (g[axis].clamp(-MAX_GRADIENT, MAX_GRADIENT) as f32).to_bits()));
        }
        words.extend(&image.shadowed);
        let planes = Buffer::with_data(ctx, vk::BufferUsageFlags::TRANSFER_SRC, &words, name)?;
        Ok(Self { planes, size: (image.width, image.height) })
    }

    /// The copies into the range view's attachments and `shadowed`.
    pub fn step<'s>(&'s self, range: &'s ViewTargets, shadowed: &'s Buffer) -> Step<'s> {
        let (w, h) = self.size;
        let plane_bytes = u64::from(w) * u64::from(h) * 4;
        let targets: Vec<_> = range.colour.iter().map(|image| (image, Access::TransferWrite)).collect();
        let buffers = vec![(&self.planes, Access::TransferRead), (shadowed, Access::TransferWrite)];
        Step::new(targets, buffers, move |ctx: &GpuContext, cmd| {
            let d = &ctx.device;
            for (plane, image) in range.colour.iter().enumerate() {
                let region = [vk::BufferImageCopy::default()
                    .buffer_offset(plane as u64 * plane_bytes)
                    .image_subresource(
                        vk::ImageSubresourceLayers::default().aspect_mask(vk::ImageAspectFlags::COLOR).layer_count(1),
                    )
                    .image_extent(vk::Extent3D { width: w, height: h, depth: 1 })];
                // SAFETY: cmd is recording; the image is w×h in TRANSFER_DST layout (the step's
                // barrier) and the plane lies inside the buffer.
                unsafe {
                    d.cmd_copy_buffer_to_image(
                        cmd,
                        self.planes.raw,
                        image.raw,
                        vk::ImageLayout::TRANSFER_DST_OPTIMAL,
                        &region,
                    )
                };
            }
            let last =
                [vk::BufferCopy::default().src_offset((Self::PLANES as u64 - 1) * plane_bytes).size(plane_bytes)];
            // SAFETY: both buffers hold the plane (the shadowed labels are w·h words).
            unsafe { d.cmd_copy_buffer(cmd, self.planes.raw, shadowed.raw, &last) };
        })
    }
}
