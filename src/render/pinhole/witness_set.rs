//! A rig's pinhole witnesses as the GPU draws and tests them: their label images, stacked in
//! bands of rows of one attachment, and the table the label test reads (witness_mask.rs).

use super::witness_mask::WitnessConstants;
use crate::error::{Error, Result};
use crate::gpu::{Buffer, GpuContext};
use crate::sensor::{Intrinsics, PixelRect, Sensor, Witness, WitnessGeometry};
use crate::shadow::{Neighbourhood, ShadowMode, ShadowSettings};
use ash::vk;
use glam::DMat4;
use std::sync::Arc;

/// A witness as every job draws it: the move into its frame, its label image's intrinsics
/// (`columns` applied, cy counted from the top of the attachments) and its band of them.
pub(super) struct WitnessView {
    pub from_reference: DMat4,
    pub drawn: Intrinsics,
    pub band: PixelRect,
}

/// Where a rig's pinhole witnesses' label images go, and what the label test reads of each:
/// worked out on the host alone, so that a plan can be refused before anything is allocated.
pub(crate) struct WitnessLayout {
    views: Vec<WitnessView>,
    table: Vec<WitnessConstants>,
    /// Width and height of the attachment that holds every band.
    pub size: (u32, u32),
}

impl WitnessLayout {
    /// The witnesses of `sensor` under `shadow`, their label images stacked in bands of rows
    /// in file order at their own intrinsics times `[shadow] columns`; `None` where no label
    /// test runs (mode `none`, or no witnesses). Refused where they do not fit a view of
    /// `max_side` pixels a side (the device's largest).
    pub fn new(max_side: u32, sensor: &Sensor, shadow: &ShadowSettings) -> Result<Option<Self>> {
        if shadow.mode != ShadowMode::Label || sensor.witnesses.is_empty() {
            return Ok(None);
        }
        let mut row = 0u32;
        let mut views = Vec::with_capacity(sensor.witnesses.len());
        let mut table = Vec::with_capacity(sensor.witnesses.len());
        for (index, witness) in sensor.witnesses.iter().enumerate() {
            let (pose, intrinsics) = label_image(witness, index)?;
            let drawn = multiplied(&intrinsics, shadow.columns);
            let fits = |side: u64| side <= u64::from(max_side);
            if !(fits(u64::from(drawn.width)) && fits(u64::from(row) + u64::from(drawn.height))) {
                return Err(Error::Scene(format!(
                    "{}: the witnesses' label images, {} rows in all by then at [shadow] columns = {}, exceed the \
                     largest view this device draws ({max_side} pixels a side)",
                    witness.owner(index),
                    u64::from(row) + u64::from(drawn.height),
                    shadow.columns
                )));
            }
            let band = PixelRect { col: 0, row, width: drawn.width, height: drawn.height };
            table.push(WitnessConstants::new(pose, &drawn, band).ok_or_else(|| {
                Error::Scene(format!(
                    "{}: its pose is beyond what the GPU's f32 arithmetic holds",
                    witness.owner(index)
                ))
            })?);
            let drawn = Intrinsics { cy: drawn.cy + f64::from(row), ..drawn };
            views.push(WitnessView { from_reference: pose.inverse(), drawn, band });
            row += drawn.height;
        }
        let width = views.iter().map(|w| w.band.width).max().unwrap_or(0);
        Ok(Some(Self { views, table, size: (width, row) }))
    }

    /// Pixels of the attachment that holds every band.
    pub fn pixels(&self) -> u64 {
        u64::from(self.size.0) * u64::from(self.size.1)
    }
}

/// A rig's pinhole witnesses as every job of a submission draws and tests them: their layout,
/// the mask's table of them on the device, and the label test's neighbourhood.
pub(crate) struct WitnessSet {
    pub(super) views: Vec<WitnessView>,
    /// Width and height of the attachment that holds every band.
    pub size: (u32, u32),
    pub table: Buffer,
    pub neighbourhood: Neighbourhood,
}

impl WitnessSet {
    /// The witnesses of `sensor` under `shadow` laid out for `ctx`'s device ([`WitnessLayout`]),
    /// their table uploaded; `None` where no label test runs.
    pub fn new(ctx: &Arc<GpuContext>, sensor: &Sensor, shadow: &ShadowSettings) -> Result<Option<Self>> {
        let Some(layout) = WitnessLayout::new(ctx.max_view_side(), sensor, shadow)? else {
            return Ok(None);
        };
        let table = Buffer::with_data(ctx, vk::BufferUsageFlags::STORAGE_BUFFER, &layout.table, "witness table")?;
        Ok(Some(Self { views: layout.views, size: layout.size, table, neighbourhood: shadow.neighbourhood }))
    }

    /// Pixels of the attachment that holds every band.
    pub fn pixels(&self) -> u64 {
        u64::from(self.size.0) * u64::from(self.size.1)
    }
}

/// A witness's pose (reference-from-witness) and intrinsics, whose label image the label test
/// reads; a directional witness has none, and is refused by name.
pub(super) fn label_image(witness: &Witness, index: usize) -> Result<(DMat4, Intrinsics)> {
    match witness.geometry {
        WitnessGeometry::Pinhole { pose, intrinsics } => Ok((pose, intrinsics)),
        _ => Err(Error::Unsupported(format!(
            "{}: [shadow] mode = \"label\" reads pinhole witnesses' label images; a directional witness is \
             tested in modes \"depth\" and \"exact\"",
            witness.owner(index)
        ))),
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
