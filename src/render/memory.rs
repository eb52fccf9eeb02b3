//! The one memory model of a job's GPU work, which `render` checks a render against and
//! `verify` sizes its batches' slots by: what a slot holds per pixel of each view, and the
//! compute rasterizer's queue; a render adds what it reads back and returns on the host.

use crate::effects::Effects;
use crate::exact;
use crate::render::plan::Views;
use crate::render::raster::compute::{large_queue_bytes, VISIBILITY_WORD_BYTES};
use crate::render::stages::host_view::HostView;
use crate::render::stages::walk_list::WalkList;
use crate::render::targets::ViewKind;

/// Bytes a range pixel's shadowed label takes (the shadow mask's or exact mode's output).
const SHADOWED_LABEL_BYTES: u64 = 4;
/// Bytes a range pixel's witness bits take, where a rig's shadow test runs on the GPU.
const WITNESS_BITS_BYTES: u64 = 4;
/// Bytes a range pixel's effect outputs take: its loss and its measured z.
const EFFECT_OUTPUT_BYTES: u64 = 8;
/// Bytes a render reads back and returns on the host per range pixel: two readback buffers
/// (label and z: 8; the shadowed labels are read where the slot holds them, already counted)
/// and the returned label, unshadowed label, z and reason (16); with effects, their losses and
/// measured z once more (8).
const RETURNED_BYTES: u64 = 24;
/// Bytes writing a render's files takes per range pixel at its peak: the returned image (16),
/// the range image's X, Y, Z, label and reason (20), the EXR encoder's copy of them (20), and
/// the previews (4).
const WRITING_BYTES: u64 = 60;

/// GPU bytes one job's slot takes: per pixel of the range view (its attachments, the
/// shadowed labels, the effects' outputs where effects are named) and of the shadow view (its
/// attachments), and with the compute rasterizer each view's visibility words, a queue
/// with room for `compute_triangles` in each of `views` views and the shadow mask's walk list.
pub(crate) fn slot_bytes(
    (range_pixels, shadow_pixels): (u64, u64),
    effects: &Effects,
    compute_triangles: Option<u64>,
    views: u64,
) -> u64 {
    let effect_bytes = if effects.is_empty() { 0 } else { EFFECT_OUTPUT_BYTES };
    let visibility = if compute_triangles.is_some() { VISIBILITY_WORD_BYTES } else { 0 };
    let walk_list = match compute_triangles {
        Some(_) if shadow_pixels > 0 => WalkList::bytes(range_pixels),
        _ => 0,
    };
    let range = ViewKind::Range.bytes_per_pixel() + SHADOWED_LABEL_BYTES + effect_bytes + visibility;
    let shadow = ViewKind::Shadow.bytes_per_pixel() + visibility;
    let queue = compute_triangles.map_or(0, |t| large_queue_bytes(t, views));
    range * range_pixels + shadow * shadow_pixels + queue + walk_list
}

/// Bytes a render of a rig's pinhole views takes at its peak (pinhole/), rendering or writing
/// its files after: its slot ([`rig_slot_bytes`]) and what it returns on the host.
pub(crate) fn rig_render_bytes(
    (pixels, witness_pixels): (u64, u64),
    effects: &Effects,
    compute: Option<(u64, u64)>,
) -> u64 {
    let returned = RETURNED_BYTES + WITNESS_BITS_BYTES + if effects.is_empty() { 0 } else { EFFECT_OUTPUT_BYTES };
    (rig_slot_bytes((pixels, witness_pixels), effects, compute) + returned * pixels).max(WRITING_BYTES * pixels)
}

/// GPU bytes one job's slot takes under a rig's pinhole views: [`slot_bytes`] with the
/// witnesses' images of `witness_pixels` in place of a shadow view's, and each range
/// pixel's witness bits and the depth test's walk list; and where the compute rasterizer draws
/// its `views` views (raster/compute/rig.rs), `compute` = (the triangles a view's queue has
/// room for, `views`), their visibility words and queues.
pub(crate) fn rig_slot_bytes(
    (pixels, witness_pixels): (u64, u64),
    effects: &Effects,
    compute: Option<(u64, u64)>,
) -> u64 {
    let compute_bytes = compute.map_or(0, |(triangles, views)| {
        let queues = large_queue_bytes(triangles, views);
        VISIBILITY_WORD_BYTES * (pixels + witness_pixels) + queues
    });
    let walk_list = WalkList::bytes(pixels);
    slot_bytes((pixels, witness_pixels), effects, None, 1) + WITNESS_BITS_BYTES * pixels + walk_list + compute_bytes
}

/// Bytes a render on the CPU alone takes (a rig other than the paper's scanner, by exact ray
/// casting: src/exact/rig.rs) at its peak, rendering or writing its files after: `casters`
/// over `triangles`, and the image of `pixels` it casts and returns.
pub(crate) fn exact_bytes(casters: u64, triangles: u64, pixels: u64) -> u64 {
    let rendering =
        casters * triangles * exact::CASTER_BYTES_PER_TRIANGLE + (exact::BYTES_PER_PIXEL + RETURNED_BYTES) * pixels;
    rendering.max(WRITING_BYTES * pixels)
}

/// Bytes a render of these views takes at its peak, rendering or writing its files after
/// (the larger of the two): its slot ([`slot_bytes`]), what it returns on the host, and in
/// shadow mode `exact` the CPU's casters and image (exact.rs) and their upload
/// (stages/host_view.rs).
pub(crate) fn render_bytes(
    views: &Views,
    effects: &Effects,
    compute_triangles: Option<u64>,
    exact_triangles: Option<u64>,
) -> u64 {
    let range = u64::from(views.range.width) * u64::from(views.range.height);
    let shadow = views.shadow.map_or(0, |g| u64::from(g.width) * u64::from(g.height));
    let returned = RETURNED_BYTES + if effects.is_empty() { 0 } else { EFFECT_OUTPUT_BYTES };
    let rendering = slot_bytes((range, shadow), effects, compute_triangles, views.count()) + returned * range;
    let exact = exact_triangles
        .map_or(0, |t| t * exact::BYTES_PER_TRIANGLE + (exact::BYTES_PER_PIXEL + HostView::BYTES_PER_PIXEL) * range);
    (rendering + exact).max(WRITING_BYTES * range)
}
