//! One job's pinhole views: each draw's constants in the reference view and in every
//! witness's band, with the depth range and cull mode each view draws it with; and the table
//! of witnesses the job's shadow test reads (written into its slot's before the test), with
//! its directional witnesses' grids and, for the depth test, each witness's draw table.

use super::directional::{self, DirectionalPlan};
use super::witness_mask::{WitnessAttachment, WitnessConstants, WitnessMaskConstants};
use super::witness_set::{WitnessImage, WitnessSet};
use super::Models;
use crate::error::{Error, Result};
use crate::gpu::{Buffer, GpuContext};
use crate::render::raster::compute::RigView;
use crate::render::raster::draw::{cull_mode, Band, DrawConstants, PinholeDrawing, ViewportFrame};
use crate::render::FOOTPRINT_MARGIN;
use crate::sensor::{Intrinsics, Pinhole, PixelRect, View};
use crate::shadow::ShadowTest;
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
/// band, and the shadow test's constants over its area with the job's table of witnesses.
pub(crate) struct PinholeJob {
    /// Every pixel of the reference view.
    whole: PixelRect,
    reference: ViewDraws,
    witnesses: Vec<WitnessDraws>,
    /// What the shadow test reads of each witness, in file order.
    pub witness_table: Vec<WitnessConstants>,
    /// The depth test's draw tables, whose addresses `witness_table` holds: the job keeps them
    /// alive.
    _draw_tables: Option<Buffer>,
    pub mask: WitnessMaskConstants,
    /// How far, in pixels, the draws' corners may reach from the first pixel of a directional
    /// witness's band (the compute rasterizer takes the job where it is within
    /// `MAX_REACH_PIXELS`: Renderer::computes_rig; it clips a pinhole view's triangles to the
    /// viewport, as the graphics pipeline does, so they reach no farther).
    pub reach: f64,
}

/// A witness's band: its attachment, the pixels of it the job draws (where the models can
/// cover it), the viewport it is drawn through, and each draw's constants and cull mode in it.
struct WitnessDraws {
    attachment: WitnessAttachment,
    band: PixelRect,
    area: PixelRect,
    viewport: ViewportFrame,
    draws: ViewDraws,
}

impl PinholeJob {
    /// The job that draws `models` under the pinhole `reference` view (and `witnesses`, in
    /// modes `label` and `depth`) over `area` of it (a hypothesis' footprint, or the whole image), with the
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
        // The compute rasterizer clips a pinhole view's triangles to its viewport (raster.comp,
        // clipped_polygon): only a directional witness's band has a reach to bound.
        let mut reach: f64 = 0.0;
        for (w, constants) in views.iter().zip(&mut table) {
            let drawn = match w.image {
                WitnessImage::Pinhole(intrinsics) => {
                    pinhole_witness(w.from_reference, intrinsics, w.band, &models, viewport_half_side)?
                }
                WitnessImage::Directional(image) => {
                    let plan = directional::plan(w.from_reference, (image, w.band), reference, &models);
                    *constants = constants.with_grid(plan.band_grid);
                    let reach_of = |&(centre, radius): &(DVec3, f64)| {
                        plan.grid.reach(plan.from_reference.transform_point3(centre), radius)
                    };
                    reach = models.spheres.iter().map(reach_of).fold(reach, f64::max);
                    directional_witness(&plan, w.band, &models, viewport_half_side)?
                }
            };
            witness_draws.push(drawn);
        }
        // The depth test walks each witness's draws in its frame: their constants in its band,
        // one table a witness, in one buffer.
        let walked = witnesses.is_some_and(|set| set.test == ShadowTest::Depth);
        let draw_tables = walked
            .then(|| {
                let entries: Vec<DrawConstants> =
                    witness_draws.iter().flat_map(|w| w.draws.iter().map(|&(constants, _)| constants)).collect();
                Buffer::with_data(ctx, vk::BufferUsageFlags::STORAGE_BUFFER, &entries, "a job's witness draw tables")
            })
            .transpose()?;
        // Each witness's pixels the job draws (the tests read no other), and its draw table.
        let table_bytes = (models.draws.len() * size_of::<DrawConstants>()) as u64;
        for ((k, constants), drawn) in (0..).zip(&mut table).zip(&witness_draws) {
            let draws = draw_tables.as_ref().map_or(0, |tables| tables.device_address() + k * table_bytes);
            *constants = constants.with_job(drawn.area, draws);
        }
        let reference = view_draws(&reference_drawing, &models, ViewportFrame::around(whole, viewport_half_side))?;
        Ok(Self {
            whole,
            reference,
            witnesses: witness_draws,
            mask: WitnessMaskConstants::new(&k, area, views.len()),
            witness_table: table,
            _draw_tables: draw_tables,
            reach,
        })
    }

    /// The job's views as the compute rasterizer draws them (raster/compute/rig.rs), in the
    /// order of [`rig_views`](super::rig_views): the reference view over `area` (the job's),
    /// then each witness's band, in file order, over the pixels of it the models can cover,
    /// resolved over its rows of what the job draws of its attachment.
    pub fn compute_views(&self, area: PixelRect) -> Vec<RigView<'_>> {
        let reference = RigView { area, resolved: area, draws: &self.reference };
        let witnesses = self.witnesses.iter().map(|w| {
            let drawn = self.witness_area(w.attachment);
            let first = drawn.row.max(w.band.row);
            let end = (drawn.row + drawn.height).min(w.band.row + w.band.height);
            let rows = PixelRect { row: first, height: end.saturating_sub(first), ..drawn };
            RigView { area: w.area, resolved: rows, draws: &w.draws }
        });
        std::iter::once(reference).chain(witnesses).collect()
    }

    /// The reference view's width and height.
    pub fn size(&self) -> (u32, u32) {
        (self.whole.width, self.whole.height)
    }

    /// The reference view, drawn over `area` (the job's).
    pub fn reference_band(&self, area: PixelRect, viewport_half_side: f32) -> Band<'_> {
        Band { area, viewport: ViewportFrame::around(self.whole, viewport_half_side), draws: &self.reference }
    }

    /// The bands of one of the witnesses' attachments, each drawn where the models can cover
    /// it.
    pub fn witness_bands(&self, attachment: WitnessAttachment) -> Vec<Band<'_>> {
        self.witnesses
            .iter()
            .filter(|w| w.attachment == attachment)
            .map(|w| Band { area: w.area, viewport: w.viewport, draws: &w.draws })
            .collect()
    }

    /// The pixels of one of the witnesses' attachments that the job draws (and clears): every
    /// band's where the models can cover it. The shadow test reads no other.
    pub fn witness_area(&self, attachment: WitnessAttachment) -> PixelRect {
        let bands = self.witnesses.iter().filter(|w| w.attachment == attachment);
        bands.map(|w| w.area).fold(PixelRect::EMPTY, PixelRect::union)
    }
}

/// A pinhole witness's band for `models`: its image `drawn` (cy counted from the top of
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
    // The pixels of its image the models can cover: the shadow test reads no other, as every
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
    Ok(WitnessDraws { attachment: WitnessAttachment::Pinhole, band, area, viewport, draws })
}

/// A directional witness's band for `models` as `plan` places it: each draw's constants on
/// its grid and cull mode (a proper rotation: the scanner's shadow view's).
fn directional_witness(
    plan: &DirectionalPlan,
    band: PixelRect,
    models: &Models,
    viewport_half_side: f32,
) -> Result<WitnessDraws> {
    let viewport = ViewportFrame::new(&plan.grid, viewport_half_side);
    let draws = models
        .draws
        .iter()
        .enumerate()
        .map(|(i, draw)| {
            let constants =
                DrawConstants::new(&plan.grid, plan.from_reference, DVec3::ZERO, draw, i as u32, viewport_half_side);
            let constants =
                constants.held_in_f32().ok_or_else(|| beyond_f32(models, i, "a directional witness's view"))?;
            Ok((constants, cull_mode(draw.mesh.solidity)))
        })
        .collect::<Result<_>>()?;
    Ok(WitnessDraws { attachment: WitnessAttachment::Directional, band, area: plan.area, viewport, draws })
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
