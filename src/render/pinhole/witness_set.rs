//! A rig's witnesses as the GPU draws and tests them in shadow mode `label`: their label
//! images, stacked in bands of rows of two attachments (pinhole witnesses' images in
//! projection, directional witnesses' orthographic images), and what the label test reads of
//! each (witness_mask.rs).

use super::witness_mask::WitnessConstants;
use crate::error::{Error, Result};
use crate::gpu::GpuContext;
use crate::sensor::{Intrinsics, PixelRect, Sensor, WitnessGeometry};
use crate::shadow::{Neighbourhood, ShadowMode, ShadowSettings};
use glam::{DMat4, DQuat, DVec3};
use std::sync::Arc;

/// The most a directional witness's label image is enlarged for its slant from the reference
/// view's axis ([`WitnessLayout::new`]).
const MAX_DIRECTIONAL_FORESHORTENING: f64 = 4.0;

/// A witness as every job draws it: the move into its frame, its label image and its band of
/// its attachment.
pub(super) struct WitnessView {
    pub from_reference: DMat4,
    pub image: WitnessImage,
    pub band: PixelRect,
}

/// A witness's label image.
pub(super) enum WitnessImage {
    /// A pinhole witness's: its intrinsics times `[shadow] columns`, cy counted from the top
    /// of the pinhole witnesses' attachment. The witness's frame is its own (x right, y down,
    /// z forward).
    Pinhole(Intrinsics),
    /// A directional witness's: an orthographic image `side` pixels square, each job's planned
    /// over its models (job.rs). The witness's frame turns its direction to +z, so that it
    /// looks down −z as the paper's views do (larger z is nearer the witness).
    Directional { side: u32 },
}

/// Where a rig's witnesses' label images go, and what the label test reads of each: worked out
/// on the host alone, so that a plan can be refused before anything is allocated.
pub(crate) struct WitnessLayout {
    views: Vec<WitnessView>,
    /// What the label test reads of each witness; a directional witness's grid is each job's.
    table: Vec<WitnessConstants>,
    /// Width and height of the attachment that holds the pinhole witnesses' bands, and of the
    /// one that holds the directional witnesses' (0 × 0 where there are none).
    pub sizes: [(u32, u32); 2],
}

impl WitnessLayout {
    /// The witnesses of `sensor` under `shadow`, their label images stacked in bands of rows
    /// in file order: a pinhole witness's at its own intrinsics times `[shadow] columns`, a
    /// directional witness's a square as many pixels a side as the reference view's larger
    /// side times `columns`, over the cosine of its slant from the reference's optical axis.
    /// `None` where no label test runs (mode `none`, or no witnesses).
    /// Refused where they do not fit a view of `max_side` pixels a side (the device's
    /// largest).
    pub fn new(max_side: u32, sensor: &Sensor, shadow: &ShadowSettings) -> Result<Option<Self>> {
        if shadow.mode != ShadowMode::Label || sensor.witnesses.is_empty() {
            return Ok(None);
        }
        let (width, height) = sensor.reference.size();
        let sides = f64::from(width.max(height)) * f64::from(shadow.columns);
        let mut rows = [0u64; 2];
        let mut views = Vec::with_capacity(sensor.witnesses.len());
        let mut table = Vec::with_capacity(sensor.witnesses.len());
        for (index, witness) in sensor.witnesses.iter().enumerate() {
            let (attachment, size) = match witness.geometry {
                WitnessGeometry::Pinhole { intrinsics, .. } => {
                    let drawn = multiplied(&intrinsics, shadow.columns);
                    (0, (u64::from(drawn.width), u64::from(drawn.height)))
                }
                WitnessGeometry::Directional(direction) => {
                    // A surface facing the reference view is foreshortened by the cosine of the
                    // witness's slant from the reference's axis as the witness sees it: so many
                    // more pixels keep the image as fine as the reference's points (at most 4×).
                    let slant = direction.vector().normalize().z.abs().max(1.0 / MAX_DIRECTIONAL_FORESHORTENING);
                    let side = (sides / slant).ceil() as u64;
                    (1, (side, side))
                }
            };
            let row = rows[attachment];
            let fits = |side: u64| side <= u64::from(max_side);
            if !(fits(size.0) && fits(row + size.1)) {
                return Err(Error::Scene(format!(
                    "{}: the witnesses' label images, {} rows in all by then at [shadow] columns = {}, exceed the \
                     largest view this device draws ({max_side} pixels a side)",
                    witness.owner(index),
                    row + size.1,
                    shadow.columns
                )));
            }
            // Both fit in a u32 now.
            let band = PixelRect { col: 0, row: row as u32, width: size.0 as u32, height: size.1 as u32 };
            let unheld = || {
                Error::Scene(format!(
                    "{}: its pose is beyond what the GPU's f32 arithmetic holds",
                    witness.owner(index)
                ))
            };
            let (from_reference, image, constants) = match witness.geometry {
                WitnessGeometry::Pinhole { pose, intrinsics } => {
                    let drawn = multiplied(&intrinsics, shadow.columns);
                    let constants = WitnessConstants::pinhole(pose, &drawn, band).ok_or_else(unheld)?;
                    let drawn = Intrinsics { cy: drawn.cy + f64::from(band.row), ..drawn };
                    (pose.inverse(), WitnessImage::Pinhole(drawn), constants)
                }
                WitnessGeometry::Directional(direction) => {
                    let toward = direction.vector().normalize();
                    let from_reference = DMat4::from_quat(DQuat::from_rotation_arc(toward, DVec3::Z));
                    let constants = WitnessConstants::directional(from_reference, toward, band);
                    (from_reference, WitnessImage::Directional { side: band.width }, constants)
                }
            };
            views.push(WitnessView { from_reference, image, band });
            table.push(constants);
            rows[attachment] += size.1;
        }
        let size = |attachment: usize| {
            let bands =
                views.iter().filter(|w| matches!(w.image, WitnessImage::Directional { .. }) == (attachment == 1));
            (bands.map(|w| w.band.width).max().unwrap_or(0), rows[attachment] as u32)
        };
        let sizes = [size(0), size(1)];
        Ok(Some(Self { views, table, sizes }))
    }

    /// Pixels of the attachments that hold every band.
    pub fn pixels(&self) -> u64 {
        self.sizes.iter().map(|&(w, h)| u64::from(w) * u64::from(h)).sum()
    }
}

/// A rig's witnesses as every job of a submission draws and tests them: their layout and the
/// label test's neighbourhood. Each job uploads the mask's table of them (job.rs), which
/// holds its directional witnesses' grids.
pub(crate) struct WitnessSet {
    pub(super) views: Vec<WitnessView>,
    pub(super) table: Vec<WitnessConstants>,
    /// Width and height of the pinhole witnesses' attachment and of the directional
    /// witnesses' (0 × 0 where there are none).
    pub sizes: [(u32, u32); 2],
    pub neighbourhood: Neighbourhood,
}

impl WitnessSet {
    /// The witnesses of `sensor` under `shadow` laid out for `ctx`'s device ([`WitnessLayout`]);
    /// `None` where no label test runs.
    pub fn new(ctx: &Arc<GpuContext>, sensor: &Sensor, shadow: &ShadowSettings) -> Result<Option<Self>> {
        let Some(layout) = WitnessLayout::new(ctx.max_view_side(), sensor, shadow)? else {
            return Ok(None);
        };
        let WitnessLayout { views, table, sizes } = layout;
        Ok(Some(Self { views, table, sizes, neighbourhood: shadow.neighbourhood }))
    }

    /// Pixels of the attachments that hold every band.
    pub fn pixels(&self) -> u64 {
        self.sizes.iter().map(|&(w, h)| u64::from(w) * u64::from(h)).sum()
    }
}

/// A witness's label image: its intrinsics with `columns` = k pixels to each of the
/// witness's, in both axes (pixel centres stay at whole image coordinates).
fn multiplied(k: &Intrinsics, columns: u32) -> Intrinsics {
    let c = f64::from(columns);
    let centre_shift = (c - 1.0) / 2.0;
    Intrinsics {
        width: k.width * columns,
        height: k.height * columns,
        fx: k.fx * c,
        fy: k.fy * c,
        cx: k.cx * c + centre_shift,
        cy: k.cy * c + centre_shift,
    }
}
