//! A rig's witnesses as the GPU draws and tests them in shadow modes `label` and `depth`: their
//! images (visibility: label, draw index, triangle), stacked in bands of rows of two
//! attachments (pinhole witnesses' images in projection, directional witnesses' orthographic
//! images), and what the shadow test reads of each (witness_mask.rs).

use super::directional::DirectionalImage;
use super::witness_mask::{WitnessAttachment, WitnessConstants};
use crate::error::{Error, Result};
use crate::gpu::GpuContext;
use crate::sensor::{Intrinsics, PixelRect, Sensor, View, WitnessGeometry};
use crate::shadow::{ShadowSettings, ShadowTest};
use glam::{DMat4, DQuat, DVec3};
use std::sync::Arc;

/// The most a directional witness's image is enlarged for its slant from the reference
/// view's axis ([`WitnessLayout::new`]).
const MAX_DIRECTIONAL_FORESHORTENING: f64 = 4.0;

/// A witness as every job draws it: the move into its frame, its image and its band of its
/// attachment.
pub(super) struct WitnessView {
    pub from_reference: DMat4,
    pub image: WitnessImage,
    pub band: PixelRect,
}

/// A witness's image.
pub(super) enum WitnessImage {
    /// A pinhole witness's: its intrinsics times `[shadow] columns`, cy counted from the top
    /// of the pinhole witnesses' attachment. The witness's frame is its own (x right, y down,
    /// z forward).
    Pinhole(Intrinsics),
    /// A directional witness's: an orthographic image, each job's planned over its models
    /// (directional.rs). The witness's frame turns its direction to +z, so that it looks down
    /// −z as the paper's views do (larger z is nearer the witness).
    Directional(DirectionalImage),
}

/// Where a rig's witnesses' images go, and what the shadow test reads of each: worked out
/// on the host alone, so that a plan can be refused before anything is allocated.
pub(crate) struct WitnessLayout {
    views: Vec<WitnessView>,
    /// What the shadow test reads of each witness; a directional witness's grid (and, in the
    /// depth test, every witness's draw table) is each job's.
    table: Vec<WitnessConstants>,
    /// Width and height of each attachment ([`WitnessAttachment`]), 0 × 0 where no witness's
    /// band lies in it.
    pub sizes: [(u32, u32); 2],
    /// The shadow test that reads them.
    test: ShadowTest,
}

impl WitnessLayout {
    /// The witnesses of `sensor` under `shadow`, their images stacked in bands of rows in file
    /// order: a pinhole witness's at its own intrinsics times `[shadow] columns`, a
    /// directional witness's a square as many pixels a side as the reference view's larger
    /// side times `columns`, over the cosine of its slant from the reference's optical axis.
    /// `None` where no shadow test runs on the GPU (modes `none` and `exact`, or no
    /// witnesses).
    /// Refused where they do not fit a view of `max_side` pixels a side (the device's
    /// largest).
    pub fn new(max_side: u32, sensor: &Sensor, shadow: &ShadowSettings) -> Result<Option<Self>> {
        let Some(test) = shadow.test().filter(|_| !sensor.witnesses.is_empty()) else {
            return Ok(None);
        };
        let (width, height) = sensor.reference.size();
        let sides = f64::from(width.max(height)) * f64::from(shadow.columns);
        // A pixel's width at depth 1 is 1 / f.
        let focal = match &sensor.reference {
            View::Pinhole(p) => p.intrinsics.fx.max(p.intrinsics.fy),
            _ => f64::INFINITY,
        };
        let mut rows = [0u64; 2];
        let mut views: Vec<(WitnessAttachment, WitnessView)> = Vec::with_capacity(sensor.witnesses.len());
        let mut table = Vec::with_capacity(sensor.witnesses.len());
        for (index, witness) in sensor.witnesses.iter().enumerate() {
            let unheld = || {
                Error::Scene(format!(
                    "{}: its pose is beyond what the GPU's f32 arithmetic holds",
                    witness.owner(index)
                ))
            };
            // Its attachment and image's size, then its view and table entry in its band.
            type InBand<'w> = Box<dyn FnOnce(PixelRect) -> Result<(WitnessView, WitnessConstants)> + 'w>;
            let (attachment, size, in_band): (_, _, InBand) = match witness.geometry {
                WitnessGeometry::Pinhole { pose, intrinsics } => {
                    let drawn = multiplied(&intrinsics, shadow.columns);
                    let in_band = move |band: PixelRect| {
                        let constants = WitnessConstants::pinhole(pose, &drawn, band).ok_or_else(unheld)?;
                        let image = WitnessImage::Pinhole(Intrinsics { cy: drawn.cy + f64::from(band.row), ..drawn });
                        Ok((WitnessView { from_reference: pose.inverse(), image, band }, constants))
                    };
                    (WitnessAttachment::Pinhole, (u64::from(drawn.width), u64::from(drawn.height)), Box::new(in_band))
                }
                WitnessGeometry::Directional(direction) => {
                    let toward = direction.vector().normalize();
                    // A surface facing the reference view is foreshortened, as the witness sees
                    // it, by the cosine of the witness's slant from the reference's axis: so
                    // many more pixels keep the image as fine as the reference's points.
                    let slant = toward.z.abs().max(1.0 / MAX_DIRECTIONAL_FORESHORTENING);
                    let side = (sides / slant).ceil() as u64;
                    let finest = slant / (focal * f64::from(shadow.columns));
                    let in_band = move |band: PixelRect| {
                        let from_reference = DMat4::from_quat(DQuat::from_rotation_arc(toward, DVec3::Z));
                        let constants = WitnessConstants::directional(from_reference, toward, band);
                        let image = WitnessImage::Directional(DirectionalImage { side: band.width, finest });
                        Ok((WitnessView { from_reference, image, band }, constants))
                    };
                    (WitnessAttachment::Directional, (side, side), Box::new(in_band))
                }
            };
            let row = rows[attachment as usize];
            let fits = |side: u64| side <= u64::from(max_side);
            if !(fits(size.0) && fits(row + size.1)) {
                return Err(Error::Scene(format!(
                    "{}: the witnesses' images, {} rows in all by then at [shadow] columns = {}, exceed the \
                     largest view this device draws ({max_side} pixels a side)",
                    witness.owner(index),
                    row + size.1,
                    shadow.columns
                )));
            }
            // Both fit in a u32 now.
            let band = PixelRect { col: 0, row: row as u32, width: size.0 as u32, height: size.1 as u32 };
            let (view, constants) = in_band(band)?;
            views.push((attachment, view));
            table.push(constants);
            rows[attachment as usize] += size.1;
        }
        let sizes = WitnessAttachment::ALL.map(|attachment| {
            let widths = views.iter().filter(|(a, _)| *a == attachment).map(|(_, w)| w.band.width);
            (widths.max().unwrap_or(0), rows[attachment as usize] as u32)
        });
        let views = views.into_iter().map(|(_, view)| view).collect();
        Ok(Some(Self { views, table, sizes, test }))
    }

    /// Pixels of the attachments that hold every band.
    pub fn pixels(&self) -> u64 {
        self.sizes.iter().map(|&(w, h)| u64::from(w) * u64::from(h)).sum()
    }
}

/// A rig's witnesses as every job of a submission draws and tests them: their layout, the
/// shadow test, and the mask's table of them as far as it is the same for every job (a
/// directional witness's grid, and the depth test's draw tables, are each job's: job.rs).
pub(crate) struct WitnessSet {
    pub(super) views: Vec<WitnessView>,
    pub(super) table: Vec<WitnessConstants>,
    /// Width and height of each attachment ([`WitnessAttachment`]), 0 × 0 where no witness's
    /// band lies in it.
    pub sizes: [(u32, u32); 2],
    pub test: ShadowTest,
}

impl WitnessSet {
    /// The witnesses of `sensor` under `shadow` laid out for `ctx`'s device ([`WitnessLayout`]);
    /// `None` where no shadow test runs on the GPU.
    pub fn new(ctx: &Arc<GpuContext>, sensor: &Sensor, shadow: &ShadowSettings) -> Result<Option<Self>> {
        let Some(layout) = WitnessLayout::new(ctx.max_view_side(), sensor, shadow)? else {
            return Ok(None);
        };
        let WitnessLayout { views, table, sizes, test } = layout;
        Ok(Some(Self { views, table, sizes, test }))
    }

    /// Pixels of the attachments that hold every band.
    pub fn pixels(&self) -> u64 {
        self.sizes.iter().map(|&(w, h)| u64::from(w) * u64::from(h)).sum()
    }
}

/// A witness's image: its intrinsics with `columns` = k pixels to each of the
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
