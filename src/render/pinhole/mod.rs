//! A rig's pinhole views on the GPU (docs/sensors-and-rigs.md, "On the GPU"): the reference
//! view and, in shadow modes `label` and `depth`, every witness's image, drawn by the graphics
//! pipeline in projection (shaders/raster/draw.glsl, `pinhole_clip_position`); then the shadow
//! test of each reference pixel's point against every witness, in one compute pass
//! (witness_mask.rs): the paper's label test, or the depth test's walk toward the witness. A job's passes (src/render/passes.rs) draw them in place of the
//! scanner's range and shadow passes, so that `render` reads them back and `verify` scores
//! them in its batches as it does the scanner's.
//!
//! The witnesses share two sets of attachments, one band of rows each: the pinhole witnesses'
//! images, drawn in projection, and the directional witnesses', drawn orthographically by the
//! scanner's shadow-view pipelines over each job's models; the mask binds two images whatever
//! their number.

mod directional;
mod job;
mod pipelines;
mod witness_mask;
mod witness_set;

pub(crate) use job::PinholeJob;
pub use pipelines::PinholePipelines;
pub(crate) use witness_mask::{MaskWords, WitnessAttachment, WitnessMaskBindings, WitnessTable};
pub(crate) use witness_set::{WitnessLayout, WitnessSet};

use super::memory::rig_render_bytes;
use super::raster::compute::{RigTarget, COVERAGE_MEMBERS};
use super::raster::draw::{Draw, Projection};
use super::{GpuMesh, RenderOutput, Renderer, Source, Views, FOOTPRINT_MARGIN};
use crate::error::{Error, Result};
use crate::render::Crossover;
use crate::scene::Scene;
use crate::sensor::{Pinhole, Sensor, View};
use crate::shadow::{ShadowMode, ShadowTest};
use glam::DVec3;
use std::sync::Arc;
use witness_set::WitnessImage;

/// Whether the GPU draws a rig: a pinhole reference view in shadow modes `none`, `label` and
/// `depth`. Mode `label` under an orthographic reference view other than the paper's scanner
/// is refused: the label test reads a pinhole reference view's points.
pub(crate) fn draws_rig(sensor: &Sensor, mode: ShadowMode) -> Result<bool> {
    let pinhole = matches!(sensor.reference, View::Pinhole(_));
    match mode {
        ShadowMode::None | ShadowMode::Depth => Ok(pinhole),
        ShadowMode::Label if !pinhole => Err(Error::Unsupported(
            "[shadow] mode = \"label\" reads the witnesses' label images at a pinhole reference view's points; \
             under an orthographic reference view other than the paper's scanner, use mode \"depth\" or \"exact\""
                .into(),
        )),
        ShadowMode::Label => Ok(true),
        _ => Ok(false),
    }
}

/// A rig's views as the compute rasterizer draws them (raster/compute/rig.rs): the pinhole
/// reference view, then each witness's band in `witnesses` (none without a shadow test on the
/// GPU), each with the attachments it is resolved into and its projection.
pub(crate) fn rig_views(witnesses: Option<&WitnessSet>) -> Vec<(RigTarget, Projection)> {
    let bands = witnesses.into_iter().flat_map(|set| &set.views).map(|w| match w.image {
        WitnessImage::Pinhole(_) => (RigTarget::Witnesses(WitnessAttachment::Pinhole as usize), Projection::Pinhole),
        WitnessImage::Directional(_) => {
            (RigTarget::Witnesses(WitnessAttachment::Directional as usize), Projection::Orthographic)
        }
    });
    std::iter::once((RigTarget::Reference, Projection::Pinhole)).chain(bands).collect()
}

/// What a rig's views draw: the draws, their models' bounding spheres (reference frame), and
/// how an error names draw i.
pub(crate) struct Models<'a> {
    pub draws: &'a [Draw<'a>],
    pub spheres: &'a [(DVec3, f64)],
    pub name: &'a dyn Fn(usize) -> String,
}

impl Renderer {
    /// Draws a scene whose rig the GPU draws ([`draws_rig`]) on `views` (the reference view's
    /// pixels): the reference view's labels, depths and gradients, and in modes `label` and
    /// `depth` the witnesses' shadow test, as exact ray casting would return them, then its
    /// effects.
    pub(super) fn render_pinhole_rig(&self, scene: &Scene, views: &Views) -> Result<RenderOutput> {
        let View::Pinhole(reference) = scene.sensor.reference else {
            return Err(Error::Unsupported("the GPU draws a pinhole reference view only".into()));
        };
        self.check_pinhole(&reference)?;
        let witnesses = WitnessSet::new(&self.ctx, &scene.sensor, &scene.shadow)?;
        let pixels = u64::from(views.range.width) * u64::from(views.range.height);
        let witness_pixels = witnesses.as_ref().map_or(0, WitnessSet::pixels);
        // A view's queue has room for every triangle of every draw, up to COVERAGE_MEMBERS of
        // them, the compute rasterizer's most (raster/compute/rig.rs).
        let largest = scene.objects.iter().map(|o| o.mesh.triangles.len() as u64).max().unwrap_or(0);
        let queued = largest * scene.objects.len().min(COVERAGE_MEMBERS) as u64;
        let compute = self.may_compute().then(|| (queued, rig_views(witnesses.as_ref()).len() as u64));
        self.ledger.check(
            format_args!("drawing a {}×{} pinhole view and its witnesses", views.range.width, views.range.height),
            rig_render_bytes((pixels, witness_pixels), &scene.effects, compute),
        )?;
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
        let models = Models { draws: &draws, spheres: &spheres, name: &name };
        let half_side = self.ctx.viewport_half_side();
        let whole = views.range.full();
        let job = PinholeJob::new(&self.ctx, &reference, witnesses.as_ref(), models, whole, half_side)?;
        // The compute rasterizer's choice reads the pixels the objects can cover.
        let footprint: u64 = spheres
            .iter()
            .filter_map(|&(centre, radius)| scene.sensor.reference.footprint(centre, radius, FOOTPRINT_MARGIN))
            .map(|area| area.pixels())
            .sum();
        let compute = self.computes_rig(&job, &draws, footprint, witnesses.as_ref());
        let source = Source::Pinhole { job: &job, witnesses: witnesses.as_ref(), compute };
        self.render_views(scene, None, views, &draws, source)
    }

    /// Whether the compute rasterizer draws `job`'s views (raster/compute/rig.rs), `draws`
    /// over `footprint_pixels` of the reference view (their bounding spheres' pixels, with a
    /// margin, together): as [`Renderer::computes`] decides for a view of
    /// the same draws and pixels, whose words are the largest of the reference view's and the
    /// `witnesses`' attachments', and whose reach is the job's (its directional witnesses'),
    /// `auto` following the rigs' crossover ([`Renderer::rig_crossover`]).
    pub(crate) fn computes_rig(
        &self,
        job: &PinholeJob,
        draws: &[Draw],
        footprint_pixels: u64,
        witnesses: Option<&WitnessSet>,
    ) -> bool {
        let triangles: u64 = draws.iter().map(|draw| u64::from(draw.mesh.index_count / 3)).sum();
        let largest = draws.iter().map(|draw| u64::from(draw.mesh.index_count / 3)).max().unwrap_or(0);
        let (width, height) = job.size();
        let attachments = witnesses.into_iter().flat_map(|set| set.sizes);
        let view_pixels = std::iter::once((width, height))
            .chain(attachments)
            .map(|(w, h)| u64::from(w) * u64::from(h))
            .max()
            .unwrap_or(0);
        let depth_test = witnesses.is_some_and(|set| set.test == ShadowTest::Depth);
        let crossover = Crossover::for_rig(self.ctx.is_cpu(), depth_test && draws.len() == 1);
        self.computes_past(crossover, draws.len(), (triangles, largest), (footprint_pixels, job.reach), view_pixels)
    }

    /// Refuses what the GPU cannot draw of a pinhole reference view: a view larger than the
    /// device's largest.
    pub(crate) fn check_pinhole(&self, reference: &Pinhole) -> Result<()> {
        let k = reference.intrinsics;
        let max_side = self.ctx.max_view_side();
        if k.width.max(k.height) > max_side {
            return Err(Error::Scene(format!(
                "[sensor]: a {}×{} image is larger than the largest view this device draws ({max_side} pixels a side)",
                k.width, k.height
            )));
        }
        Ok(())
    }
}
