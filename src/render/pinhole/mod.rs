//! A rig's pinhole views on the GPU (docs/sensors-and-rigs.md, "On the GPU"): the reference
//! view and, in shadow mode `label`, every witness's label image, drawn by the graphics
//! pipeline in projection (shaders/raster/draw.glsl, `pinhole_clip_position`); then the paper's
//! label test of each reference pixel's point against every witness, in one compute pass
//! (witness_mask.rs). One submission; its images are read back as a cast image, which the
//! effect passes and the summary take as they take exact mode's.
//!
//! The witnesses share one set of attachments, one band of rows each, drawn in one rendering:
//! the mask binds one image whatever their number.

mod pipelines;
mod witness_mask;

pub use pipelines::PinholePipelines;

use super::raster::draw::{cull_mode, record_bands, Band, Draw, DrawConstants, PinholeDrawing, ViewportFrame};
use super::targets::{ViewKind, ViewTargets};
use super::{Cast, GpuMesh, PassTime, Raster, Renderer};
use crate::error::{Error, Result};
use crate::exact::ExactImage;
use crate::gpu::{Access, Buffer, BufferDesc, Encoder, Timestamps};
use crate::scene::Scene;
use crate::sensor::{Intrinsics, PixelRect, Sensor, View, Witness, WitnessGeometry};
use crate::shadow::{ShadowMode, ShadowSettings};
use ash::vk;
use glam::{DMat4, DVec3};
use std::sync::Arc;
use witness_mask::{WitnessConstants, WitnessMaskBindings, WitnessMaskConstants};

/// Where the near plane goes when the sensor sets none (`near = 0`) and a model reaches the
/// plane of a view's centre: this fraction of the farthest depth any model reaches. A surface
/// nearer than that to the view's centre is not drawn.
const NEAR_FRACTION: f64 = 1.0 / 1048576.0;

/// Whether the GPU draws a rig: a pinhole reference view in shadow mode `none`, or in mode
/// `label` with pinhole witnesses alone. Mode `label` on any other rig is refused, naming what
/// the label test cannot read.
pub(crate) fn draws_rig(sensor: &Sensor, mode: ShadowMode) -> Result<bool> {
    let pinhole = matches!(sensor.reference, View::Pinhole(_));
    match mode {
        ShadowMode::None => Ok(pinhole),
        ShadowMode::Label if !pinhole => Err(Error::Unsupported(
            "[shadow] mode = \"label\" reads the witnesses' label images at a pinhole reference view's points; \
             under an orthographic reference view other than the paper's scanner, use mode \"depth\" or \"exact\""
                .into(),
        )),
        ShadowMode::Label => {
            for (index, witness) in sensor.witnesses.iter().enumerate() {
                label_image(witness, index)?;
            }
            Ok(true)
        }
        _ => Ok(false),
    }
}

/// A witness's pose (reference-from-witness) and intrinsics, whose label image the label test
/// reads; a directional witness has none, and is refused by name.
fn label_image(witness: &Witness, index: usize) -> Result<(DMat4, Intrinsics)> {
    match witness.geometry {
        WitnessGeometry::Pinhole { pose, intrinsics } => Ok((pose, intrinsics)),
        _ => Err(Error::Unsupported(format!(
            "{}: [shadow] mode = \"label\" reads pinhole witnesses' label images; a directional witness is \
             tested in modes \"depth\" and \"exact\"",
            witness.owner(index)
        ))),
    }
}

/// The depth constants of a pinhole view (draw.glsl, `pinhole_clip_position`) for models
/// whose bounding spheres are `spheres` (reference frame; `view_from_reference` moves them
/// into the view's): s at the nearest depth any model reaches, but no nearer than `near`, nor
/// than [`NEAR_FRACTION`] of the farthest.
fn depth_constants(spheres: &[(DVec3, f64)], view_from_reference: DMat4, (near, far): (f64, f64)) -> [f64; 2] {
    let in_view = spheres.iter().map(|&(c, r)| (view_from_reference.transform_point3(c), r));
    let (nearest, farthest) =
        in_view.fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), (c, r)| (lo.min(c.z - r), hi.max(c.z + r)));
    // Nothing in front of the view: any s will do.
    let s = if farthest > 0.0 { near.max(nearest).max(farthest * NEAR_FRACTION) } else { 1.0 };
    match far.is_finite() && far > s {
        // The near plane stays at s: s′ / (1 + s′ / far) = s.
        true => {
            let s = s / (1.0 - s / far);
            [s, s / far]
        }
        false => [s, 0.0],
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

/// What a rig's views draw: the draws, their models' bounding spheres (reference frame), and
/// how an error names draw i.
pub(crate) struct Models<'a> {
    pub draws: &'a [Draw<'a>],
    pub spheres: &'a [(DVec3, f64)],
    pub name: &'a dyn Fn(usize) -> String,
}

/// One witness as drawn: its drawing, its band of the witnesses' attachments, and what the
/// mask reads of it.
struct WitnessView {
    drawing: PinholeDrawing,
    band: PixelRect,
    mask: WitnessConstants,
}

impl Renderer {
    /// Draws a scene whose rig the GPU draws ([`draws_rig`]): the reference view's labels,
    /// depths and gradients, and in mode `label` the witnesses' label test, as exact ray
    /// casting would return them.
    pub(super) fn render_pinhole_rig(&self, scene: &Scene) -> Result<Cast> {
        let label_bases = scene.label_bases()?;
        // The lowest label last among ties (draw.rs).
        let mut order: Vec<usize> = (0..scene.objects.len()).collect();
        order.sort_by_key(|&i| std::cmp::Reverse(label_bases[i]));
        let meshes: Vec<Arc<GpuMesh>> =
            order.iter().map(|&i| self.meshes.get(&self.ctx, &scene.objects[i].mesh)).collect::<Result<_>>()?;
        let draws: Vec<Draw> = order
            .iter()
            .zip(&meshes)
            .map(|(&i, mesh)| Draw { mesh, pose: scene.objects[i].pose, label_base: label_bases[i] })
            .collect();
        let spheres: Vec<(DVec3, f64)> = order
            .iter()
            .map(|&i| {
                let (centre, radius) = scene.objects[i].mesh.bounding_sphere();
                (scene.objects[i].pose.transform_point3(centre), radius)
            })
            .collect();
        let name = |draw: usize| {
            let i = order[draw];
            format!("object {} ({})", i + 1, scene.objects[i].model_ref)
        };
        let (width, height) = scene.sensor.reference.size();
        let whole = PixelRect { col: 0, row: 0, width, height };
        let models = Models { draws: &draws, spheres: &spheres, name: &name };
        self.draw_pinhole_rig(&scene.sensor, &scene.shadow, models, whole)
    }

    /// Draws `models` under a rig whose reference view is a pinhole one, within `area` of the
    /// reference view (a hypothesis' footprint; nothing is seen outside it).
    pub(crate) fn draw_pinhole_rig(
        &self,
        sensor: &Sensor,
        shadow: &ShadowSettings,
        Models { draws, spheres, name }: Models,
        area: PixelRect,
    ) -> Result<Cast> {
        let View::Pinhole(reference) = sensor.reference else {
            return Err(Error::Unsupported("the GPU draws a pinhole reference view only".into()));
        };
        if self.raster == Raster::Compute {
            return Err(Error::Unsupported(
                "the compute rasterizer draws the paper's scanner's orthographic views only; a pinhole \
                 reference view is drawn by the graphics pipeline (--raster graphics or auto)"
                    .into(),
            ));
        }
        let k = reference.intrinsics;
        let max_side = self.ctx.max_view_side();
        if k.width.max(k.height) > max_side {
            return Err(Error::Scene(format!(
                "[sensor]: a {}×{} image is larger than the largest view this device draws ({max_side} pixels a side)",
                k.width, k.height
            )));
        }
        let ctx = &self.ctx;
        let pipelines = self.pipelines.pinhole()?;
        let reference_drawing = PinholeDrawing {
            view_from_reference: DMat4::IDENTITY,
            intrinsics: [k.fx, k.fy, k.cx, k.cy],
            size: (k.width, k.height),
            depth: depth_constants(spheres, DMat4::IDENTITY, (reference.near, reference.far)),
        };
        let witnesses = match shadow.mode {
            ShadowMode::Label => self.witness_views(sensor, shadow.columns, spheres)?,
            _ => Vec::new(),
        };
        let band_width = witnesses.iter().map(|w| w.band.width).max().unwrap_or(0);
        let band_height = witnesses.last().map_or(0, |w| w.band.row + w.band.height);
        let pixels = u64::from(k.width) * u64::from(k.height);
        let band_pixels = u64::from(band_width) * u64::from(band_height);
        // The reference view's attachments and their read-back planes, its masked labels and
        // witness bits, and the witnesses' attachments.
        let planes = ViewKind::Range.colour_attachments().len() as u64;
        self.ledger.check(
            format_args!("drawing a {}×{} pinhole view and its witnesses", k.width, k.height),
            pixels * (ViewKind::Range.bytes_per_pixel() + 4 * planes + 8)
                + band_pixels * ViewKind::Shadow.bytes_per_pixel(),
        )?;
        self.check_pixel_buffers((k.width, k.height))?;
        let half_side = ctx.viewport_half_side();
        // Each draw's constants and cull mode in a view: a solid's back faces are culled only
        // where its bounding sphere lies wholly beyond the near plane. Else the view may lie
        // inside it, or the near plane cut it open, and its inside be seen.
        let constants = |drawing: &PinholeDrawing, area: PixelRect| {
            let viewport = ViewportFrame::around(area, half_side);
            draws
                .iter()
                .zip(spheres)
                .enumerate()
                .map(|(i, (draw, &(sphere, radius)))| {
                    let constants = DrawConstants::pinhole(drawing, draw, i as u32, viewport).ok_or_else(|| {
                        Error::Scene(format!(
                            "{}: its pose puts it beyond what the GPU's f32 arithmetic holds in a pinhole view",
                            name(i)
                        ))
                    })?;
                    let nearest = drawing.view_from_reference.transform_point3(sphere).z - radius;
                    let whole = nearest > drawing.near_plane();
                    let cull = if whole { cull_mode(draw.mesh.solidity) } else { vk::CullModeFlags::NONE };
                    Ok((constants, cull))
                })
                .collect::<Result<Vec<_>>>()
        };
        let whole = PixelRect { col: 0, row: 0, width: k.width, height: k.height };
        let reference_constants = constants(&reference_drawing, whole)?;
        let witness_constants = witnesses.iter().map(|w| constants(&w.drawing, w.band)).collect::<Result<Vec<_>>>()?;

        let reference_targets = ViewTargets::new(ctx, ViewKind::Range, k.width, k.height, "pinhole reference view")?;
        let readback = Buffer::new(ctx, BufferDesc::readback(pixels * 4 * planes), "pinhole view readback")?;
        let masked = Buffer::new(ctx, BufferDesc::readback(pixels * 4), "masked labels readback")?;
        let lost_by = Buffer::new(ctx, BufferDesc::readback(pixels * 4), "witness bits readback")?;
        let witness_targets = (!witnesses.is_empty())
            .then(|| ViewTargets::new(ctx, ViewKind::Shadow, band_width, band_height, "pinhole witness views"))
            .transpose()?;
        let table: Vec<WitnessConstants> = witnesses.iter().map(|w| w.mask).collect();
        let mask_pipeline = pipelines.mask(shadow.neighbourhood);
        let mask = witness_targets
            .as_ref()
            .map(|targets| -> Result<_> {
                let table = Buffer::with_data(ctx, vk::BufferUsageFlags::STORAGE_BUFFER, &table, "witness table")?;
                let bindings = WitnessMaskBindings::new(
                    ctx,
                    mask_pipeline,
                    (&reference_targets, targets),
                    (&masked, &lost_by, &table),
                )?;
                Ok((table, bindings))
            })
            .transpose()?;
        let mask_constants = WitnessMaskConstants::new(&k, area, witnesses.len());

        let timestamps = Timestamps::new(ctx, 2, "pinhole views timestamps")?;
        ctx.submit_and_wait("pinhole views", |cmd| {
            timestamps.reset(cmd);
            timestamps.write(cmd, 0);
            let mut enc = Encoder::new(ctx, cmd);
            let images: Vec<_> = std::iter::once(&reference_targets)
                .chain(&witness_targets)
                .flat_map(|targets| {
                    let colour = targets.colour.iter().map(|image| (image, Access::ColorAttachmentWrite));
                    colour.chain([(&targets.depth, Access::DepthAttachmentWrite)])
                })
                .collect();
            enc.access(&images, &[]);
            let layout = self.pipelines.raster_layout;
            let by_index = |list: &[(DrawConstants, vk::CullModeFlags)]| {
                let list = list.to_vec();
                move |_: &Draw, index: u32| list[index as usize]
            };
            let reference_band = by_index(&reference_constants);
            let band = Band { area, viewport: ViewportFrame::around(whole, half_side), constants: &reference_band };
            record_bands(ctx, cmd, (&pipelines.reference, layout), &reference_targets, area, &[band], draws, 0);
            if let (Some(targets), Some((_, bindings))) = (&witness_targets, &mask) {
                let lookups: Vec<_> = witness_constants.iter().map(|list| by_index(list)).collect();
                let bands: Vec<Band> = witnesses
                    .iter()
                    .zip(&lookups)
                    .map(|(w, lookup)| Band {
                        area: w.band,
                        viewport: ViewportFrame::around(w.band, half_side),
                        constants: lookup,
                    })
                    .collect();
                let all = PixelRect { col: 0, row: 0, width: band_width, height: band_height };
                record_bands(ctx, cmd, (&pipelines.witnesses, layout), targets, all, &bands, draws, 0);
                let mut read: Vec<_> = reference_targets.colour.iter().map(|i| (i, Access::ComputeRead)).collect();
                read.extend(targets.colour.iter().map(|i| (i, Access::ComputeRead)));
                enc.access(&read, &[(&masked, Access::ComputeWrite), (&lost_by, Access::ComputeWrite)]);
                bindings.record(cmd, mask_pipeline, &mask_constants);
            }
            let colour: Vec<_> = reference_targets.colour.iter().map(|i| (i, Access::TransferRead)).collect();
            enc.access(&colour, &[(&readback, Access::TransferWrite)]);
            for (plane, image) in (0..).zip(&reference_targets.colour) {
                image.record_copy_to_buffer(cmd, &readback, plane * pixels * 4, (k.width, k.height));
            }
            let host = [(&readback, Access::HostRead), (&masked, Access::HostRead), (&lost_by, Access::HostRead)];
            enc.access(&[], &host);
            timestamps.write(cmd, 1);
            Ok(())
        })?;
        let time = PassTime { name: "pinhole views", ms: timestamps.millis_between(0, 1)?, on_cpu: false };

        let words: Vec<u32> = readback.read()?;
        let plane = |i: usize| &words[i * pixels as usize..(i + 1) * pixels as usize];
        // Outside `area` nothing was drawn, nor cleared.
        let inside = |at: usize| area.contains(at as u32 % k.width, at as u32 / k.width);
        let label: Vec<u32> = plane(0).iter().enumerate().map(|(at, &l)| if inside(at) { l } else { 0 }).collect();
        let float = |i: usize, at: usize| f64::from(f32::from_bits(plane(i)[at]));
        let hit = |at: usize| label[at] != 0;
        let z = (0..label.len()).map(|at| if hit(at) { float(1, at) } else { 0.0 }).collect();
        let gradient =
            (0..label.len()).map(|at| if hit(at) { [float(2, at), float(3, at)] } else { [0.0; 2] }).collect();
        let (shadowed, witness) = match mask {
            Some(_) => {
                let outside_zero = |words: Vec<u32>| {
                    words.into_iter().enumerate().map(|(at, w)| if inside(at) { w } else { 0 }).collect::<Vec<_>>()
                };
                (outside_zero(masked.read()?), outside_zero(lost_by.read()?))
            }
            None => (label.clone(), vec![0; label.len()]),
        };
        let image = ExactImage { width: k.width, height: k.height, label, shadowed, z, gradient, witness };
        Ok(Cast { image, time })
    }

    /// The witnesses' label images, stacked in bands of rows in file order, each at its own
    /// intrinsics times `[shadow] columns`. Refused where they do not fit the device's largest
    /// view.
    fn witness_views(&self, sensor: &Sensor, columns: u32, spheres: &[(DVec3, f64)]) -> Result<Vec<WitnessView>> {
        let max_side = self.ctx.max_view_side();
        let mut row = 0u32;
        let mut views = Vec::with_capacity(sensor.witnesses.len());
        for (index, witness) in sensor.witnesses.iter().enumerate() {
            let (pose, intrinsics) = label_image(witness, index)?;
            let drawn = multiplied(&intrinsics, columns);
            let fits = |side: u64| side <= u64::from(max_side);
            if !(fits(u64::from(drawn.width)) && fits(u64::from(row) + u64::from(drawn.height))) {
                return Err(Error::Scene(format!(
                    "{}: the witnesses' label images, {} rows in all by then at [shadow] columns = {}, exceed the \
                     largest view this device draws ({max_side} pixels a side)",
                    witness.owner(index),
                    u64::from(row) + u64::from(drawn.height),
                    columns
                )));
            }
            let band = PixelRect { col: 0, row, width: drawn.width, height: drawn.height };
            let from_reference = pose.inverse();
            let drawing = PinholeDrawing {
                view_from_reference: from_reference,
                intrinsics: [drawn.fx, drawn.fy, drawn.cx, drawn.cy + f64::from(row)],
                size: (drawn.width, drawn.height),
                depth: depth_constants(spheres, from_reference, (0.0, f64::INFINITY)),
            };
            let mask = WitnessConstants::new(pose, &drawn, band).ok_or_else(|| {
                Error::Scene(format!(
                    "{}: its pose is beyond what the GPU's f32 arithmetic holds",
                    witness.owner(index)
                ))
            })?;
            views.push(WitnessView { drawing, band, mask });
            row += drawn.height;
        }
        Ok(views)
    }
}
