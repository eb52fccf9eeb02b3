//! One job's pinhole views: each draw's constants in the reference view and in every
//! witness's band, with the depth range and cull mode each view draws it with; and the table
//! of witnesses the job's label test reads, with its directional witnesses' grids.

use super::witness_mask::WitnessMaskConstants;
use super::witness_set::{WitnessImage, WitnessSet};
use super::Models;
use crate::error::{Error, Result};
use crate::gpu::{Buffer, GpuContext};
use crate::render::raster::draw::{cull_mode, Band, DrawConstants, PinholeDrawing, ViewportFrame};
use crate::render::FOOTPRINT_MARGIN;
use crate::sensor::{Intrinsics, Pinhole, PixelRect, View, ViewGrid};
use ash::vk;
use glam::{DMat4, DVec3};
use std::sync::Arc;

/// The near plane lies no nearer than this fraction of the farthest depth any model reaches
/// (f32 depths s / Z stay normal): a surface nearer than that to the view's centre is not
/// drawn, whatever the sensor's `near`.
const NEAR_FRACTION: f64 = 1.0 / 1048576.0;

/// What the nearest depth a model's bounding sphere reaches is multiplied by to place the near
/// plane (a margin of 2⁻¹⁰ of it).
const NEAR_MARGIN: f64 = 1.0 - 1.0 / 1024.0;

/// Each draw's constants and cull mode in one view.
type ViewDraws = Vec<(DrawConstants, vk::CullModeFlags)>;

/// One job's pinhole views: its draws' constants in the reference view and in each witness's
/// band, and the label test's constants over its area with the job's table of witnesses.
pub(crate) struct PinholeJob {
    /// Every pixel of the reference view.
    whole: PixelRect,
    reference: ViewDraws,
    witnesses: Vec<WitnessDraws>,
    /// What the label test reads of each witness, where it runs; `mask` holds its address.
    _table: Option<Buffer>,
    pub mask: WitnessMaskConstants,
}

/// A witness's band of its attachment (the pinhole witnesses', or the directional
/// witnesses'), the pixels of it the job's models can cover, the viewport it is drawn
/// through, and each draw's constants and cull mode in it.
struct WitnessDraws {
    directional: bool,
    area: PixelRect,
    viewport: ViewportFrame,
    draws: ViewDraws,
}

impl PinholeJob {
    /// The job that draws `models` under the pinhole `reference` view (and `witnesses`, in
    /// mode `label`) over `area` of it (a hypothesis' footprint, or the whole image), with the
    /// device's `viewport_half_side`.
    pub fn new(
        ctx: &Arc<GpuContext>,
        reference: &Pinhole,
        witnesses: Option<&WitnessSet>,
        models: Models,
        area: PixelRect,
        viewport_half_side: f32,
    ) -> Result<Self> {
        let k = reference.intrinsics;
        let whole = PixelRect { col: 0, row: 0, width: k.width, height: k.height };
        let reference_drawing = PinholeDrawing {
            view_from_reference: DMat4::IDENTITY,
            intrinsics: [k.fx, k.fy, k.cx, k.cy],
            size: (k.width, k.height),
            depth: depth_constants(models.spheres, DMat4::IDENTITY, (reference.near, reference.far)),
        };
        let (views, mut table) = witnesses.map_or((&[][..], Vec::new()), |set| (&set.views[..], set.table.clone()));
        let mut witness_draws = Vec::with_capacity(views.len());
        for (w, constants) in views.iter().zip(&mut table) {
            let drawn = match w.image {
                WitnessImage::Pinhole(intrinsics) => {
                    pinhole_witness(w.from_reference, intrinsics, w.band, &models, viewport_half_side)?
                }
                WitnessImage::Directional { side } => {
                    // Planned over the whole image, not the job's area: a hypothesis' label
                    // test is the same in a batch as drawn alone.
                    let (grid, drawn) = directional_witness(
                        w.from_reference,
                        (side, w.band),
                        (reference, whole),
                        &models,
                        viewport_half_side,
                    )?;
                    *constants = constants.with_grid(grid);
                    drawn
                }
            };
            witness_draws.push(drawn);
        }
        let table = (!table.is_empty())
            .then(|| Buffer::with_data(ctx, vk::BufferUsageFlags::STORAGE_BUFFER, &table, "a job's witnesses"))
            .transpose()?;
        Ok(Self {
            whole,
            reference: view_draws(&reference_drawing, &models, ViewportFrame::around(whole, viewport_half_side))?,
            witnesses: witness_draws,
            mask: WitnessMaskConstants::new(&k, area, (table.as_ref(), views.len())),
            _table: table,
        })
    }

    /// The reference view, drawn over `area` (the job's).
    pub fn reference_band(&self, area: PixelRect, viewport_half_side: f32) -> Band<'_> {
        Band { area, viewport: ViewportFrame::around(self.whole, viewport_half_side), draws: &self.reference }
    }

    /// The bands of the pinhole witnesses' attachment (`directional` false) or of the
    /// directional witnesses', each drawn where the models can cover it.
    pub fn witness_bands(&self, directional: bool) -> Vec<Band<'_>> {
        self.witnesses
            .iter()
            .filter(|w| w.directional == directional)
            .map(|w| Band { area: w.area, viewport: w.viewport, draws: &w.draws })
            .collect()
    }

    /// The pixels of the pinhole witnesses' attachment (`directional` false) or of the
    /// directional witnesses' that the job draws (and clears): every band's where the models
    /// can cover it. The label test reads no other.
    pub fn witness_area(&self, directional: bool) -> PixelRect {
        let bands = self.witnesses.iter().filter(|w| w.directional == directional);
        bands.map(|w| w.area).fold(PixelRect::EMPTY, PixelRect::union)
    }
}

/// A pinhole witness's band for `models`: its label image `drawn` (cy counted from the top of
/// the attachment), drawn where the models can cover it.
fn pinhole_witness(
    from_reference: DMat4,
    drawn: Intrinsics,
    band: PixelRect,
    models: &Models,
    viewport_half_side: f32,
) -> Result<WitnessDraws> {
    let drawing = PinholeDrawing {
        view_from_reference: from_reference,
        intrinsics: [drawn.fx, drawn.fy, drawn.cx, drawn.cy],
        size: (drawn.width, drawn.height),
        depth: depth_constants(models.spheres, from_reference, (0.0, f64::INFINITY)),
    };
    // The pixels of its image the models can cover: the label test reads no other, as every
    // point it tests lies on a model.
    let image = Intrinsics { cy: drawn.cy - f64::from(band.row), ..drawn };
    let image = View::Pinhole(Pinhole { intrinsics: image, near: 0.0, far: f64::INFINITY });
    let seen = models
        .spheres
        .iter()
        .filter_map(|&(c, r)| image.footprint(from_reference.transform_point3(c), r, FOOTPRINT_MARGIN))
        .fold(PixelRect::EMPTY, PixelRect::union);
    let area = PixelRect { row: seen.row + band.row, ..seen };
    let viewport = ViewportFrame::around(band, viewport_half_side);
    let draws = view_draws(&drawing, models, viewport)?;
    Ok(WitnessDraws { directional: false, area, viewport, draws })
}

/// A directional witness's band for `models`: an orthographic image `side` pixels square in
/// the witness's frame (`from_reference` turns its direction to +z) over the square that holds,
/// with a pixel to spare each way, every point of the models the reference view can see over
/// `area` (`seen_box`). Returns its grid as the label test reads it (x0, y0 of the band's first
/// pixel, dx, dy) and the band's draws.
fn directional_witness(
    from_reference: DMat4,
    (side, band): (u32, PixelRect),
    (reference, area): (&Pinhole, PixelRect),
    models: &Models,
    viewport_half_side: f32,
) -> Result<([f64; 4], WitnessDraws)> {
    let corners = |[low, high]: [DVec3; 2], to: DMat4| {
        (0..8).map(move |i| {
            let pick = |bit: usize, l: f64, h: f64| if i & bit == 0 { l } else { h };
            to.transform_point3(DVec3::new(pick(1, low.x, high.x), pick(2, low.y, high.y), pick(4, low.z, high.z)))
        })
    };
    let bound = |points: &mut dyn Iterator<Item = DVec3>| {
        points.fold([DVec3::INFINITY, DVec3::NEG_INFINITY], |[low, high], p| [low.min(p), high.max(p)])
    };
    // Every model's depths in the witness's frame (all it draws), and the part of its box
    // the reference view can see over `area`.
    let (mut depths, mut seen) = ((f64::INFINITY, f64::NEG_INFINITY), [DVec3::INFINITY, DVec3::NEG_INFINITY]);
    for draw in models.draws {
        let posed = draw.pose * DMat4::from_translation(draw.mesh.origin);
        let [low, high] = bound(&mut corners(draw.mesh.bounding_box, from_reference * posed));
        depths = (depths.0.min(low.z), depths.1.max(high.z));
        let [near, far] = bound(&mut corners(draw.mesh.bounding_box, posed)).map(|p| p.z);
        let (near, far) = (near.max(reference.near).max(0.0), far.min(reference.far));
        if near.is_nan() || far.is_nan() || near > far {
            continue;
        }
        // The frustum over `area` between those depths, in the witness's frame: the point at
        // depth Z on the ray through the image point (u, v) of each corner of the area.
        let k = &reference.intrinsics;
        let (left, right) = (f64::from(area.col) - 0.5, f64::from(area.col + area.width) - 0.5);
        let (top, bottom) = (f64::from(area.row) - 0.5, f64::from(area.row + area.height) - 0.5);
        let frustum = corners([DVec3::new(left, top, near), DVec3::new(right, bottom, far)], DMat4::IDENTITY)
            .map(|p| from_reference.transform_point3(p.z * DVec3::new((p.x - k.cx) / k.fx, (p.y - k.cy) / k.fy, 1.0)));
        let [f_low, f_high] = bound(&mut frustum.into_iter());
        let (low, high) = (low.max(f_low), high.min(f_high));
        if low.x <= high.x && low.y <= high.y {
            seen = [seen[0].min(low), seen[1].max(high)];
        }
    }
    let [low, high] = seen;
    let found = low.x <= high.x && low.y <= high.y && depths.0 <= depths.1;
    let extent = if found { (high.x - low.x).max(high.y - low.y).max(f64::MIN_POSITIVE) } else { 1.0 };
    let pitch = extent / f64::from(side.saturating_sub(2).max(1));
    let centre = if found { (low + high) / 2.0 } else { DVec3::ZERO };
    let half = f64::from(side - 1) / 2.0 * pitch;
    let (x0, top) = (centre.x - half, centre.y + half);
    let z_range = if found { (depths.0 - pitch, depths.1 + pitch) } else { (0.0, 1.0) };
    // The attachment's rows from its first: the band's first row lies at `top`.
    let grid = ViewGrid {
        origin: [x0, top + f64::from(band.row) * pitch],
        pitch: [pitch, pitch],
        width: side,
        height: band.row + side,
        z_range,
    };
    let viewport = ViewportFrame::new(&grid, viewport_half_side);
    let draws = models
        .draws
        .iter()
        .enumerate()
        .map(|(i, draw)| {
            let constants = DrawConstants::new(&grid, from_reference, DVec3::ZERO, draw, i as u32, viewport_half_side);
            let constants =
                constants.held_in_f32().ok_or_else(|| beyond_f32(models, i, "a directional witness's view"))?;
            Ok((constants, cull_mode(draw.mesh.solidity)))
        })
        .collect::<Result<_>>()?;
    let area = if found { band } else { PixelRect::EMPTY };
    Ok(([x0, top, pitch, pitch], WitnessDraws { directional: true, area, viewport, draws }))
}

/// Model i's pose holds no f32 value in `view`.
fn beyond_f32(models: &Models, i: usize, view: &str) -> Error {
    Error::Scene(format!("{}: its pose puts it beyond what the GPU's f32 arithmetic holds in {view}", (models.name)(i)))
}

/// Each draw's constants and cull mode in a view: a solid's back faces are culled only where
/// its bounding sphere lies wholly beyond the near plane. Else the view may lie inside it, or
/// the near plane cut it open, and its inside be seen.
fn view_draws(drawing: &PinholeDrawing, models: &Models, viewport: ViewportFrame) -> Result<ViewDraws> {
    models
        .draws
        .iter()
        .zip(models.spheres)
        .enumerate()
        .map(|(i, (draw, &(sphere, radius)))| {
            let constants = DrawConstants::pinhole(drawing, draw, i as u32, viewport)
                .ok_or_else(|| beyond_f32(models, i, "a pinhole view"))?;
            let nearest = drawing.view_from_reference.transform_point3(sphere).z - radius;
            let whole = nearest > drawing.near_plane();
            Ok((constants, if whole { cull_mode(draw.mesh.solidity) } else { vk::CullModeFlags::NONE }))
        })
        .collect()
}
/// The depth constants of a pinhole view (draw.glsl, `pinhole_clip_position`) for models
/// whose bounding spheres are `spheres` (reference frame; `view_from_reference` moves them
/// into the view's): s at the nearest depth any model reaches, but no nearer than `near`, nor
/// than [`NEAR_FRACTION`] of the farthest.
fn depth_constants(spheres: &[(DVec3, f64)], view_from_reference: DMat4, (near, far): (f64, f64)) -> [f64; 2] {
    let in_view = spheres.iter().map(|&(c, r)| (view_from_reference.transform_point3(c), r));
    let (nearest, farthest) =
        in_view.fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), (c, r)| (lo.min(c.z - r), hi.max(c.z + r)));
    // Nothing in front of the view: any s will do. The nearest point is moved nearer by a hair,
    // so that f32 rounding of the constants cannot clip a vertex that touches its sphere.
    let s = if farthest > 0.0 { near.max(nearest * NEAR_MARGIN).max(farthest * NEAR_FRACTION) } else { 1.0 };
    match (far.is_finite(), far > s) {
        (false, _) => [s, 0.0],
        // The near plane stays at s: s′ / (1 + s′ / far) = s.
        (true, true) => {
            let s = s / (1.0 - s / far);
            [s, s / far]
        }
        // Every model lies beyond `far`: the far plane cuts them all.
        (true, false) => [s, s / far],
    }
}
