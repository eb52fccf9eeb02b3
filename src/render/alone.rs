//! Models drawn one by one, each alone, under a rig's pinhole views, and read back: what scoring
//! a BOP results file needs (src/bop/), many estimates of one image at once. Each model is a
//! job within its footprint; as many jobs as the renderer keeps slots go in one submission.

use super::pinhole::{draws_rig, rig_views, Models, PinholeJob, WitnessSet};
use super::{rig_slot_bytes, Draw, GpuMesh, Job, Renderer, Sink, SinkKind, SlotShape, Views, FOOTPRINT_MARGIN};
use crate::effects::Effects;
use crate::error::{Error, Result};
use crate::gpu::{Buffer, BufferDesc, Encoder};
use crate::mesh::Mesh;
use crate::sensor::{PixelRect, Sensor, View};
use crate::shadow::ShadowSettings;
use glam::DMat4;
use std::sync::Arc;

/// Most models one submission draws.
const MODELS_A_SUBMISSION: usize = 8;

/// What a rig's views show of one model drawn alone, a word a pixel of the reference view
/// (row by row): its label (0 where it is not seen), the same with 0 where a witness does not
/// see the point, and the depth Z along the optical axis (0 where it is not seen).
pub struct DrawnAlone {
    pub label: Vec<u32>,
    pub shadowed: Vec<u32>,
    pub z: Vec<f32>,
}

impl Renderer {
    /// Draws each of `models` (a mesh and its pose, camera-from-model) alone under `sensor`,
    /// whose reference view is a pinhole one, in shadow mode `none`, `label` or `depth`
    /// (`pinhole::draws_rig`), within its footprint; `name(i)` names model i in errors.
    pub fn draw_alone(
        &self,
        sensor: &Sensor,
        shadow: &ShadowSettings,
        models: &[(Arc<Mesh>, DMat4)],
        name: &dyn Fn(usize) -> String,
    ) -> Result<Vec<DrawnAlone>> {
        let View::Pinhole(reference) = sensor.reference else {
            return Err(Error::Unsupported("the GPU draws a pinhole reference view only".into()));
        };
        if !draws_rig(sensor, shadow.mode)? {
            return Err(Error::Unsupported(format!(
                "the GPU draws a rig's pinhole views in shadow modes \"none\", \"label\" and \"depth\", not \"{}\"",
                shadow.mode.as_str()
            )));
        }
        if models.is_empty() {
            return Ok(Vec::new());
        }
        sensor.validate()?;
        shadow.validate()?;
        self.check_pinhole(&reference)?;
        let ctx = &self.ctx;
        let (width, height) = (reference.intrinsics.width, reference.intrinsics.height);
        self.check_pixel_buffers((width, height))?;
        let pixels = u64::from(width) * u64::from(height);
        let witnesses = WitnessSet::new(ctx, sensor, shadow)?;
        let witness_pixels = witnesses.as_ref().map_or(0, WitnessSet::pixels);
        let slots = models.len().min(MODELS_A_SUBMISSION);
        // Each slot and its read-back label and z; each model's returned image.
        let largest = models.iter().map(|(mesh, _)| mesh.triangles.len() as u64).max().unwrap_or(0);
        let compute = self.may_compute().then(|| (largest, rig_views(witnesses.as_ref()).len() as u64));
        let per_slot = rig_slot_bytes((pixels, witness_pixels), &Effects::default(), compute) + 8 * pixels;
        let returned = 12 * pixels * models.len() as u64;
        self.ledger.check(
            format_args!("drawing {} models alone in a {width}×{height} pinhole view", models.len()),
            per_slot * slots as u64 + returned,
        )?;
        let meshes: Vec<Arc<GpuMesh>> =
            models.iter().map(|(mesh, _)| self.meshes.get(ctx, mesh)).collect::<Result<_>>()?;
        let draws: Vec<[Draw; 1]> =
            meshes.iter().zip(models).map(|(mesh, &(_, pose))| [Draw { mesh, pose, label_base: 0 }]).collect();
        let spheres: Vec<_> = models
            .iter()
            .map(|(mesh, pose)| {
                let (centre, radius) = mesh.bounding_sphere();
                (pose.transform_point3(centre), radius)
            })
            .collect();
        let footprints: Vec<Option<PixelRect>> = spheres
            .iter()
            .map(|&(centre, radius)| sensor.reference.footprint(centre, radius, FOOTPRINT_MARGIN))
            .collect();
        let half_side = ctx.viewport_half_side();
        let jobs: Vec<PinholeJob> = (0..models.len())
            .map(|i| {
                let named = |_| name(i);
                let models = Models { draws: &draws[i], spheres: &spheres[i..=i], name: &named };
                PinholeJob::new(
                    ctx,
                    &reference,
                    witnesses.as_ref(),
                    models,
                    footprints[i].unwrap_or(PixelRect::EMPTY),
                    half_side,
                )
            })
            .collect::<Result<_>>()?;
        let views = Views::cast(width, height);
        // Which models the compute rasterizer draws (raster/compute/rig.rs).
        let computes: Vec<bool> = (0..models.len())
            .map(|i| {
                self.computes_rig(
                    &jobs[i],
                    &draws[i],
                    footprints[i].map_or(0, |area| area.pixels()),
                    witnesses.as_ref(),
                )
            })
            .collect();
        let max_triangles = (0..models.len()).filter(|&i| computes[i]).map(|i| meshes[i].index_count / 3).max();
        let shape = SlotShape {
            size: (width, height),
            shadow: None,
            sink: SinkKind::Readback,
            effects: None,
            compute_raster: None,
            several_draws: false,
            from_host: false,
            witnesses: witnesses.as_ref(),
            rig_compute: max_triangles.map(|t| (t, 1)),
        };
        let slots: Vec<_> = (0..slots).map(|i| self.slot(&shape, &format!("slot {i}"))).collect::<Result<_>>()?;
        let readbacks: Vec<(Buffer, Buffer)> = (0..slots.len())
            .map(|i| {
                let buffer = |what: &str| {
                    Buffer::new(ctx, BufferDesc::readback(pixels * 4), &format!("slot {i} {what} readback"))
                };
                Ok((buffer("label")?, buffer("z")?))
            })
            .collect::<Result<_>>()?;
        let effects = Effects::default();
        let passes = self.passes((sensor, None), *shadow, &effects, (max_triangles.is_some(), true))?;
        let mut drawn = Vec::with_capacity(models.len());
        for first in (0..models.len()).step_by(slots.len()) {
            let run: Vec<usize> = (first..models.len().min(first + slots.len())).collect();
            let job = |i: usize, area: PixelRect| Job {
                draws: &draws[i],
                first_draw_index: 0,
                views: &views,
                area,
                shadow_area: None,
                reflectivity_offset: 0,
                host_view: None,
                pinhole: Some(&jobs[i]),
                compute: computes[i],
            };
            // A model whose footprint misses the image is not drawn: it shows nothing.
            let recorded: Vec<(usize, Job)> = run
                .iter()
                .enumerate()
                .filter_map(|(slot, &i)| footprints[i].map(|area| (slot, job(i, area))))
                .collect();
            let sinks: Vec<Sink> = recorded
                .iter()
                .map(|&(slot, _)| Sink::Readback { label: &readbacks[slot].0, z: &readbacks[slot].1 })
                .collect();
            ctx.submit_and_wait("models drawn alone", |cmd| {
                let mut enc = Encoder::new(ctx, cmd);
                let run: Vec<_> =
                    recorded.iter().zip(&sinks).map(|((slot, job), sink)| (&slots[*slot], job, sink)).collect();
                passes.record_run(&mut enc, &run);
                Ok(())
            })?;
            for (slot, &i) in run.iter().enumerate() {
                let Some(area) = footprints[i] else {
                    drawn.push(DrawnAlone {
                        label: vec![0; pixels as usize],
                        shadowed: vec![0; pixels as usize],
                        z: vec![0.0; pixels as usize],
                    });
                    continue;
                };
                // Outside the footprint nothing was drawn, nor cleared.
                let inside = |at: usize| area.contains(at as u32 % width, at as u32 / width);
                let kept = |words: Vec<u32>| -> Vec<u32> {
                    words.into_iter().enumerate().map(|(at, w)| if inside(at) { w } else { 0 }).collect()
                };
                let label = kept(readbacks[slot].0.read()?);
                let shadowed = match slots[slot].masked() {
                    Some(masked) => kept(masked.read()?),
                    None => label.clone(),
                };
                let z: Vec<f32> = readbacks[slot].1.read()?;
                let z = z.into_iter().zip(&label).map(|(z, &l)| if l != 0 { z } else { 0.0 }).collect();
                drawn.push(DrawnAlone { label, shadowed, z });
            }
        }
        Ok(drawn)
    }
}
