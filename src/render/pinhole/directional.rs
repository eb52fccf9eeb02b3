//! Where a job draws a directional witness's image (witness_set.rs): an orthographic
//! image along the witness's direction, planned for each job over what the reference view can
//! see of its models, since a fixed grid over everything the reference could ever see would be
//! unbounded (a pinhole view sees to infinity).

use super::Models;
use crate::sensor::{depth_margin, Pinhole, PixelRect, ViewGrid};
use glam::{DMat4, DVec3};

/// A directional witness's image as every job of a submission draws it: `side` pixels
/// square at most, and the finest pitch worth drawing per unit of depth, `finest` (a
/// reference pixel's width at depth 1, foreshortened by the witness's slant, over `columns`).
#[derive(Debug, Clone, Copy)]
pub(super) struct DirectionalImage {
    pub side: u32,
    pub finest: f64,
}

/// One job's plan of a directional witness's image in its band.
pub(super) struct DirectionalPlan {
    /// The witness's frame (the direction turned to +z), from the reference's.
    pub from_reference: DMat4,
    /// The grid the job's draws are drawn on, its rows counted from the attachment's first.
    pub grid: ViewGrid,
    /// The grid the shadow test reads: x0, y0 of the band's first pixel, dx, dy.
    pub band_grid: [f64; 4],
    /// The pixels of the attachment the job draws (and clears): the square the models' seen
    /// points fill, at the band's top left; empty where the reference view sees none of them.
    pub area: PixelRect,
}

/// Plans `image` in `band` for `models` (each drawn in full) under `reference`, in the
/// witness's frame (`from_reference` turns its direction to +z): over the square holding, with
/// a pixel to spare each way, each model's box cut by the frustum of the whole image between
/// the box's nearest and farthest depths (the whole image, not a job's area: a hypothesis tests
/// the same in a batch as drawn alone); at the pitch that square needs in
/// `image.side` pixels, or the finest worth drawing at the nearest depth seen, whichever is
/// coarser. The depth range holds every model's box whole, so that nothing is clipped.
pub(super) fn plan(
    from_reference: DMat4,
    (image, band): (DirectionalImage, PixelRect),
    reference: &Pinhole,
    models: &Models,
) -> DirectionalPlan {
    let mut depths = (f64::INFINITY, f64::NEG_INFINITY);
    let mut seen = [DVec3::INFINITY, DVec3::NEG_INFINITY];
    let mut nearest_seen = f64::INFINITY;
    let corner_rays = reference.intrinsics.corner_rays();
    for draw in models.draws {
        // The box is in the model's frame (the mesh's origin already added back).
        let in_witness = bound(corners(draw.mesh.bounding_box, from_reference * draw.pose));
        depths = (depths.0.min(in_witness[0].z), depths.1.max(in_witness[1].z));
        let [near, far] = bound(corners(draw.mesh.bounding_box, draw.pose)).map(|p| p.z);
        let (near, far) = (near.max(reference.near).max(0.0), far.min(reference.far));
        if near.is_nan() || far.is_nan() || near > far {
            continue;
        }
        // The image's frustum between those depths, in the witness's frame.
        let frustum = corner_rays.iter().flat_map(|&ray| [near * ray, far * ray]);
        let [f_low, f_high] = bound(frustum.map(|p| from_reference.transform_point3(p)));
        let (low, high) = (in_witness[0].max(f_low), in_witness[1].min(f_high));
        if low.x <= high.x && low.y <= high.y {
            seen = [seen[0].min(low), seen[1].max(high)];
            nearest_seen = nearest_seen.min(near);
        }
    }
    let [low, high] = seen;
    if !(low.x <= high.x && low.y <= high.y && depths.0 <= depths.1) {
        let grid = ViewGrid {
            origin: [0.0; 2],
            pitch: [1.0; 2],
            width: band.width,
            height: band.row + band.height,
            z_range: (0.0, 1.0),
        };
        return DirectionalPlan { from_reference, grid, band_grid: [0.0, 0.0, 1.0, 1.0], area: PixelRect::EMPTY };
    }
    let scale = low.abs().max(high.abs()).max_element().max(1.0);
    // A point-like model still gets a pitch f32 holds.
    let extent = (high.x - low.x).max(high.y - low.y).max(scale * 1e-12);
    let side = f64::from(image.side);
    let pitch = (extent / (side - 2.0).max(1.0)).max(nearest_seen * image.finest);
    // The square the seen points fill, a pixel to spare each way.
    let drawn = ((extent / pitch).ceil() + 2.0).min(side) as u32;
    let centre = (low + high) / 2.0;
    let half = f64::from(drawn - 1) / 2.0 * pitch;
    let (x0, top) = (centre.x - half, centre.y + half);
    // As the scanner's views are planned, and at least a pixel.
    let margin = depth_margin(depths.0, depths.1).max(pitch);
    let grid = ViewGrid {
        origin: [x0, top + f64::from(band.row) * pitch],
        pitch: [pitch, pitch],
        width: band.width,
        height: band.row + band.height,
        z_range: (depths.0 - margin, depths.1 + margin),
    };
    let area = PixelRect { col: band.col, row: band.row, width: drawn, height: drawn };
    DirectionalPlan { from_reference, grid, band_grid: [x0, top, pitch, pitch], area }
}

/// The eight corners of the box [low, high] moved by `to`.
fn corners([low, high]: [DVec3; 2], to: DMat4) -> impl Iterator<Item = DVec3> {
    (0..8).map(move |i| {
        let pick = |bit: usize, l: f64, h: f64| if i & bit == 0 { l } else { h };
        to.transform_point3(DVec3::new(pick(1, low.x, high.x), pick(2, low.y, high.y), pick(4, low.z, high.z)))
    })
}

/// The least and greatest corners of the box holding `points`.
fn bound(points: impl Iterator<Item = DVec3>) -> [DVec3; 2] {
    points.fold([DVec3::INFINITY, DVec3::NEG_INFINITY], |[low, high], p| [low.min(p), high.max(p)])
}
