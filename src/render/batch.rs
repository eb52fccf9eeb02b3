//! Many hypotheses per submission: for each, the range pass, the shadow pass, the shadow mask
//! and the verification counts, all recorded into one command buffer with barriers between
//! passes and no waits between hypotheses.
//!
//! Render targets live in a few slots reused round-robin; a slot's next hypothesis waits (by
//! barrier) only for that slot's previous score pass. Slot images are sized for the largest
//! view of the batch, and each hypothesis renders its own grid into them, so a hypothesis
//! renders the same alone or in any batch. Each pass touches only the hypothesis' footprint
//! (its bounding sphere's pixels, with a margin), so a small model in a large image costs
//! little; a hypothesis whose footprint misses the image records nothing. Counts go to one
//! device-local buffer, zeroed first, copied to host memory at the end.

use super::draw::{record_view, Draw, DrawConstants, ViewPass};
use super::gpu_mesh::GpuMesh;
use super::score_pass::{ScoreBindings, ScoreConstants};
use super::shadow_pass::{MaskBindings, MaskConstants};
use super::targets::{ViewKind, ViewTargets};
use super::{plan_views, Renderer, Views};
use crate::error::Result;
use crate::gpu::{address_words, barrier, Access, Buffer, BufferDesc, BufferTransition, ImageTransition};
use crate::sensor::{PixelRect, Sensor};
use crate::shadow::ShadowMode;
use ash::vk;
use glam::DMat4;

/// Render-target slots in flight within one submission.
pub const SLOTS: usize = 4;
/// Pixels added around a footprint: one for rounding, one more in the shadow view for the
/// depth test's neighbourhood of the nearest shadow pixel (shaders/shadow_mask.comp).
const FOOTPRINT_MARGIN: u32 = 2;

/// The sensed image as the score pass reads it, uploaded once per batch.
pub struct SensedBuffers<'a> {
    /// Per pixel: dense segment index + 1, or 0.
    pub segments: &'a Buffer,
    pub z: &'a Buffer,
    pub segment_count: u32,
}

/// What is constant over a batch.
pub struct BatchSettings<'a> {
    pub sensor: &'a Sensor,
    pub mode: ShadowMode,
    pub tolerance: f32,
    pub area_scale: f32,
    pub sensed: SensedBuffers<'a>,
}

/// One hypothesis: a posed mesh and where its counts go (word offsets into the batch's counts).
pub struct BatchItem<'a> {
    pub mesh: &'a GpuMesh,
    /// Bounding sphere of the mesh in model coordinates.
    pub sphere: (glam::DVec3, f64),
    pub pose: DMat4,
    pub surfaces: u32,
    /// Counts of the shadowed image (or the only image when there is no shadow pass).
    pub counts_offset: usize,
    /// Also count the unshadowed image here, when asked and a shadow pass runs.
    pub unshadowed_offset: Option<usize>,
}

impl BatchItem<'_> {
    fn draw(&self) -> Draw<'_> {
        Draw { mesh: self.mesh, pose: self.pose, label_base: 0 }
    }
}

struct Slot {
    range: ViewTargets,
    shadow: Option<ViewTargets>,
    masked: Option<Buffer>,
    mask_bindings: Option<MaskBindings>,
    score_bindings: ScoreBindings,
}

impl Renderer {
    /// Bytes of GPU memory a verification of these posed bounding spheres takes beyond the
    /// counts: its slots, each a range view (its attachments and the shadowed labels: 24
    /// bytes a pixel) and a shadow view as wide as the widest hypothesis needs (16 bytes a
    /// pixel).
    /// Fails as a batch would on a hypothesis whose views cannot be planned.
    pub(crate) fn batch_slot_memory(
        &self,
        sensor: &Sensor,
        mode: ShadowMode,
        posed_spheres: impl Iterator<Item = (glam::DVec3, f64)>,
        hypotheses: usize,
    ) -> Result<u64> {
        let max_side = self.ctx.limits.max_image_dimension2_d;
        let mut shadow_width = 0;
        for sphere in posed_spheres {
            let views = plan_views(sensor, mode, &[sphere], max_side)?;
            shadow_width = shadow_width.max(views.shadow.map_or(0, |g| g.width));
        }
        let rows = u64::from(sensor.height);
        let range_pixel = ViewKind::Range.bytes_per_pixel() + 4;
        let per_slot = rows
            * (range_pixel * u64::from(sensor.width) + ViewKind::Shadow.bytes_per_pixel() * u64::from(shadow_width));
        Ok(per_slot * SLOTS.min(hypotheses) as u64)
    }

    /// Records and runs one batch; returns the counts buffer (`counts_words` u32 words).
    pub(crate) fn count_batch(
        &self,
        settings: &BatchSettings,
        items: &[BatchItem],
        counts_words: usize,
    ) -> Result<Vec<u32>> {
        let ctx = &self.ctx;
        let d = &ctx.device;
        let p = &self.pipelines;
        let sensor = settings.sensor;
        let max_side = ctx.limits.max_image_dimension2_d;
        let views: Vec<Views> = items
            .iter()
            .map(|item| {
                let (centre, radius) = item.sphere;
                plan_views(sensor, settings.mode, &[(item.pose.transform_point3(centre), radius)], max_side)
            })
            .collect::<Result<_>>()?;
        let shadow_width = views.iter().filter_map(|v| v.shadow.map(|g| g.width)).max();
        let (w, h) = (sensor.width, sensor.height);
        let to_shadow = sensor.to_shadow_frame();
        // Hypothesis i is draw i of the shadow view.
        let draw_table = match shadow_width {
            Some(_) => {
                let entries: Vec<_> = (0..)
                    .zip(items.iter().zip(&views))
                    .filter_map(|(i, (item, views))| {
                        let grid = views.shadow.as_ref()?;
                        Some(DrawConstants::new(grid, to_shadow, views.origin, &item.draw(), i))
                    })
                    .collect();
                Some(Buffer::with_data(ctx, vk::BufferUsageFlags::STORAGE_BUFFER, &entries, "shadow draw table")?)
            }
            None => None,
        };
        let slots: Vec<Slot> = (0..SLOTS.min(items.len()))
            .map(|i| {
                let range = ViewTargets::new(ctx, ViewKind::Range, w, h, &format!("slot {i} range view"))?;
                let shadow = match shadow_width {
                    Some(sw) => Some(ViewTargets::new(ctx, ViewKind::Shadow, sw, h, &format!("slot {i} shadow view"))?),
                    None => None,
                };
                let masked = match &shadow {
                    Some(_) => Some(Buffer::new(
                        ctx,
                        BufferDesc::gpu_storage(u64::from(w) * u64::from(h) * 4),
                        &format!("slot {i} shadowed labels"),
                    )?),
                    None => None,
                };
                let mask_bindings = match (&shadow, &masked, &draw_table) {
                    (Some(s), Some(m), Some(t)) => Some(MaskBindings::new(ctx, p, &range, s, m, t)?),
                    _ => None,
                };
                let score_bindings = ScoreBindings::new(ctx, p, &range)?;
                Ok(Slot { range, shadow, masked, mask_bindings, score_bindings })
            })
            .collect::<Result<_>>()?;
        let bytes = (counts_words as u64 * 4).max(4);
        let counts = Buffer::new(ctx, BufferDesc::gpu_storage(bytes), "verification counts")?;
        let readback = Buffer::new(ctx, BufferDesc::readback(bytes), "verification counts readback")?;
        let counts_address = counts.device_address();

        ctx.submit_and_wait("verification batch", |cmd| {
            // SAFETY: cmd is recording; the buffer is not in use.
            unsafe { d.cmd_fill_buffer(cmd, counts.raw, 0, vk::WHOLE_SIZE, 0) };
            barrier(
                ctx,
                cmd,
                &[],
                &[BufferTransition { buffer: &counts, from: Access::TransferWrite, to: Access::ComputeWrite }],
            );
            let mut recorded = 0;
            for (index, (item, views)) in (0..).zip(items.iter().zip(&views)) {
                let (centre, radius) = item.sphere;
                let centre = item.pose.transform_point3(centre);
                let Some(area) = views.range.footprint(centre, radius, FOOTPRINT_MARGIN) else { continue };
                let shadow_area = views.shadow.map(|g| {
                    let c = to_shadow.transform_point3(centre);
                    let columns = g.footprint(c, radius, FOOTPRINT_MARGIN).unwrap_or(g.full());
                    // Rows are the range view's (a rotation about y keeps y).
                    PixelRect { row: area.row, height: area.height, ..columns }
                });
                let slot = &slots[recorded % slots.len()];
                let first_use = recorded < slots.len();
                recorded += 1;
                let (colour_before, depth_before) = if first_use {
                    (Access::Nothing, Access::Nothing)
                } else {
                    (Access::ComputeRead, Access::DepthAttachmentWrite)
                };
                let mut prepare = Vec::new();
                for targets in std::iter::once(&slot.range).chain(&slot.shadow) {
                    prepare.extend(targets.colour_transitions(colour_before, Access::ColorAttachmentWrite));
                    prepare.push(ImageTransition {
                        image: &targets.depth,
                        from: depth_before,
                        to: Access::DepthAttachmentWrite,
                    });
                }
                barrier(ctx, cmd, &prepare, &[]);
                let draw = [item.draw()];
                let range_pass = ViewPass {
                    pipelines: &p.range,
                    layout: p.raster_layout,
                    targets: &slot.range,
                    grid: &views.range,
                    view_from_range: DMat4::IDENTITY,
                    origin: views.origin,
                    area,
                };
                record_view(ctx, cmd, &range_pass, &draw, index);
                let mut reads = slot.range.colour_transitions(Access::ColorAttachmentWrite, Access::ComputeRead);
                let shadowed_labels =
                    match (&slot.shadow, &views.shadow, shadow_area, &slot.masked, &slot.mask_bindings) {
                        (Some(targets), Some(grid), Some(shadow_area), Some(masked), Some(bindings)) => {
                            let shadow_pass = ViewPass {
                                pipelines: &p.shadow,
                                layout: p.raster_layout,
                                targets,
                                grid,
                                view_from_range: to_shadow,
                                origin: views.origin,
                                area: shadow_area,
                            };
                            record_view(ctx, cmd, &shadow_pass, &draw, index);
                            reads.extend(targets.colour_transitions(Access::ColorAttachmentWrite, Access::ComputeRead));
                            let masked_before = if first_use { Access::Nothing } else { Access::ComputeRead };
                            barrier(
                                ctx,
                                cmd,
                                &reads,
                                &[BufferTransition { buffer: masked, from: masked_before, to: Access::ComputeWrite }],
                            );
                            bindings.record(cmd, p, &MaskConstants::new(sensor, settings.mode, views, grid, area));
                            barrier(
                                ctx,
                                cmd,
                                &[],
                                &[BufferTransition {
                                    buffer: masked,
                                    from: Access::ComputeWrite,
                                    to: Access::ComputeRead,
                                }],
                            );
                            masked.address_words()
                        }
                        _ => {
                            barrier(ctx, cmd, &reads, &[]);
                            [0, 0]
                        }
                    };
                let score = |labels: [u32; 2], offset: usize| ScoreConstants {
                    shadowed_labels: labels,
                    sensed_segments: settings.sensed.segments.address_words(),
                    sensed_z: settings.sensed.z.address_words(),
                    counts: address_words(counts_address + offset as u64 * 4),
                    width: w,
                    height: h,
                    z_origin: views.origin.z as f32,
                    _pad: 0,
                    region: [area.col, area.row, area.width, area.height],
                    surfaces: item.surfaces,
                    segments: settings.sensed.segment_count,
                    tolerance: settings.tolerance,
                    area_scale: settings.area_scale,
                    dx: sensor.pitch[0] as f32,
                    dy: sensor.pitch[1] as f32,
                };
                slot.score_bindings.record(cmd, p, &score(shadowed_labels, item.counts_offset));
                if let (Some(offset), true) = (item.unshadowed_offset, shadowed_labels != [0, 0]) {
                    slot.score_bindings.record(cmd, p, &score([0, 0], offset));
                }
            }
            barrier(
                ctx,
                cmd,
                &[],
                &[BufferTransition { buffer: &counts, from: Access::ComputeWrite, to: Access::TransferRead }],
            );
            let region = [vk::BufferCopy::default().size(bytes)];
            // SAFETY: both buffers hold `bytes` bytes; the barrier above ordered the writes.
            unsafe { d.cmd_copy_buffer(cmd, counts.raw, readback.raw, &region) };
            barrier(
                ctx,
                cmd,
                &[],
                &[BufferTransition { buffer: &readback, from: Access::TransferWrite, to: Access::HostRead }],
            );
            Ok(())
        })?;
        let mut words: Vec<u32> = readback.read()?;
        words.truncate(counts_words);
        Ok(words)
    }
}
