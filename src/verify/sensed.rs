//! The sensed image as verification needs it, computed once: its segments (the labels it
//! holds) numbered densely, each pixel's segment index, the depths, and what the scores take
//! from the sensed image alone: N_i, N_S and A_S. The per-pixel data goes to the GPU once, on
//! the first verification that needs it there, and is kept for the next.

use super::area::BlockGeometry;
use crate::error::{Error, Result};
use crate::gpu::{Buffer, GpuContext};
use crate::io::RangeImage;
use crate::sensor::{Sensor, View};
use ash::vk;
use std::sync::{Arc, OnceLock};

#[derive(Debug, Clone)]
pub struct SensedImage {
    pub width: u32,
    pub height: u32,
    /// The reference view it was measured in: a verification's sensor must have its pixels.
    pub view: View,
    /// How its blocks, and the hypotheses', turn depths into area (src/verify/area.rs).
    pub blocks: BlockGeometry,
    /// The segment labels present, ascending; dense index k stands for `segments[k]`.
    pub segments: Vec<u32>,
    /// Per pixel, the dense segment index + 1, or 0 where there is no data.
    pub(crate) segment_index: Vec<u32>,
    pub(crate) z: Vec<f32>,
    /// N_i: valid pixels.
    pub valid: u64,
    /// N_S per dense segment index.
    pub segment_population: Vec<u64>,
    /// A_S per dense segment index, in area units.
    pub segment_area_units: Vec<u64>,
    /// The device copy, once a verification made it (shared by clones: the data is the same).
    on_gpu: Arc<OnceLock<SensedGpu>>,
}

/// The sensed image's per-pixel segment indices and z in device-local memory, one pair of
/// words a pixel (segment index + 1 or 0, z's bits): the score pass reads both with one load
/// where a software rasterizer makes a load of each buffer invocation by invocation.
pub(crate) struct SensedGpu {
    /// The context the buffer belongs to.
    context: Arc<GpuContext>,
    pub pixels: Buffer,
}

impl std::fmt::Debug for SensedGpu {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("SensedGpu")
    }
}

/// The device copy a verification reads: the kept one, or one made for another device.
pub(crate) enum SensedOnGpu<'a> {
    Kept(&'a SensedGpu),
    Fresh(Box<SensedGpu>),
}

impl std::ops::Deref for SensedOnGpu<'_> {
    type Target = SensedGpu;
    fn deref(&self) -> &SensedGpu {
        match self {
            SensedOnGpu::Kept(kept) => kept,
            SensedOnGpu::Fresh(fresh) => fresh,
        }
    }
}

impl SensedImage {
    /// Host bytes a sensed image holds per pixel: its segment index and z (8), and the label
    /// copy sorted while it is built (4) or the pairs built to upload it (8).
    pub const HOST_BYTES_PER_PIXEL: u64 = 16;
    /// Device bytes per pixel once a verification uploads it: segment index and z.
    pub const GPU_BYTES_PER_PIXEL: u64 = 8;

    /// Checks the image against the sensor it is verified with and computes its statistics.
    pub fn new(image: &RangeImage, sensor: &Sensor) -> Result<Self> {
        sensor.validate()?;
        // A sensor given in place of the one the image records (`--override-sensor`) may read
        // its pixels through another pitch or other intrinsics, on request; never through
        // another kind of view, whose depths mean something else (z towards the scanner, or
        // along a pinhole's axis).
        if let Some(measured) = &image.sensor {
            check_same_kind(&measured.reference, &sensor.reference)?;
        }
        if (image.width, image.height) != (sensor.width(), sensor.height()) {
            return Err(Error::Scene(format!(
                "the sensed image is {}×{} but the sensor is {}×{}",
                image.width,
                image.height,
                sensor.width(),
                sensor.height()
            )));
        }
        let n = image.label.len();
        if image.z.len() != n || n != (image.width as usize) * (image.height as usize) {
            return Err(Error::Scene("the sensed image's channels do not match its size".into()));
        }
        // A labelled pixel needs a finite depth, and under a pinhole view one in front of its
        // centre.
        let pinhole = matches!(sensor.reference, View::Pinhole(_));
        let unmeasurable = |z: f32| !z.is_finite() || (pinhole && z <= 0.0);
        if let Some(i) = (0..n).find(|&i| image.label[i] != 0 && unmeasurable(image.z[i])) {
            let behind = if image.z[i].is_finite() { " ≤ 0, behind its pinhole view," } else { "" };
            return Err(Error::Scene(format!(
                "the sensed image has label {} but Z = {}{behind} at pixel ({}, {})",
                image.label[i],
                image.z[i],
                i % image.width as usize,
                i / image.width as usize
            )));
        }
        let mut segments: Vec<u32> = image.label.iter().copied().filter(|&l| l != 0).collect();
        segments.sort_unstable();
        segments.dedup();
        let segment_index: Vec<u32> = image
            .label
            .iter()
            .map(|&l| if l == 0 { 0 } else { segments.binary_search(&l).expect("collected above") as u32 + 1 })
            .collect();
        let mut segment_population = vec![0u64; segments.len()];
        for &k in segment_index.iter().filter(|&&k| k != 0) {
            segment_population[k as usize - 1] += 1;
        }
        // A pinhole view's area unit is a pixel's footprint at the farthest sensed depth.
        let farthest = (0..n).filter(|&i| image.label[i] != 0).map(|i| f64::from(image.z[i])).fold(0.0, f64::max);
        let blocks = BlockGeometry::of(&sensor.reference, if farthest > 0.0 { farthest } else { 1.0 });
        let unit = blocks.sides.map(|side| side as f32);
        if !(unit.iter().all(|side| side.is_normal()) && blocks.scale().is_normal()) {
            return Err(Error::Scene(format!(
                "the sensed image's farthest depth {farthest} makes an area unit of {:?} (a pixel's sides there), \
                 beyond the f32 arithmetic of the score pass",
                blocks.sides
            )));
        }
        let mut segment_area_units = vec![0u64; segments.len()];
        let (w, h) = (image.width as usize, image.height as usize);
        for r in 0..h.saturating_sub(1) {
            for c in 0..w.saturating_sub(1) {
                let i = r * w + c;
                let k = segment_index[i];
                if k != 0 && segment_index[i + 1] == k && segment_index[i + w] == k && segment_index[i + w + 1] == k {
                    let depths = [image.z[i], image.z[i + 1], image.z[i + w], image.z[i + w + 1]];
                    let units = blocks.block_units((c as u32, r as u32), depths);
                    segment_area_units[k as usize - 1] += units.iter().map(|&u| u64::from(u)).sum::<u64>();
                }
            }
        }
        Ok(Self {
            width: image.width,
            height: image.height,
            view: sensor.reference,
            blocks,
            valid: segment_population.iter().sum(),
            segments,
            segment_index,
            z: image.z.clone(),
            segment_population,
            segment_area_units,
            on_gpu: Arc::default(),
        })
    }

    /// The per-pixel data on `ctx`'s device: uploaded by the first call and kept, so a batch
    /// of `verify` calls against one image uploads it once. A call on another device gets a
    /// copy of its own.
    pub(crate) fn on_gpu(&self, ctx: &Arc<GpuContext>) -> Result<SensedOnGpu<'_>> {
        let upload = || -> Result<SensedGpu> {
            let usage = vk::BufferUsageFlags::STORAGE_BUFFER;
            Ok(SensedGpu {
                context: ctx.clone(),
                pixels: Buffer::device_local_with_data(ctx, usage, &self.gpu_pixels(), "sensed pixels")?,
            })
        };
        if self.on_gpu.get().is_none() {
            let fresh = upload()?;
            // A concurrent call may have set it first; either copy serves.
            let _ = self.on_gpu.set(fresh);
        }
        match self.on_gpu.get() {
            Some(kept) if Arc::ptr_eq(&kept.context, ctx) => Ok(SensedOnGpu::Kept(kept)),
            _ => Ok(SensedOnGpu::Fresh(Box::new(upload()?))),
        }
    }

    /// What [`SensedGpu::pixels`] holds.
    fn gpu_pixels(&self) -> Vec<[u32; 2]> {
        self.segment_index.iter().zip(&self.z).map(|(&k, z)| [k, z.to_bits()]).collect()
    }

    /// Dense index of a segment label, if the image holds it.
    pub fn segment_index(&self, label: u32) -> Option<u32> {
        self.segments.binary_search(&label).ok().map(|k| k as u32)
    }
}

/// Refuses a sensor whose reference view is of another kind than the one the sensed image was
/// measured in.
pub(super) fn check_same_kind(sensed: &View, sensor: &View) -> Result<()> {
    match sensed.kind() == sensor.kind() {
        true => Ok(()),
        false => Err(Error::Scene(format!(
            "the sensed image is a view of kind {} but the sensor's reference view is {}",
            sensed.kind(),
            sensor.kind()
        ))),
    }
}
