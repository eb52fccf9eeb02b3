//! The sensor-effect passes (src/effects.rs): one compute pipeline per effect
//! (shaders/stages/effect_*.comp, sharing shaders/stages/effect.glsl), recorded after the shadow mask, in
//! [`EFFECT_ORDER`](crate::effects::EFFECT_ORDER), only for the effects named. They write a
//! slot's losses (a [`Reason`](crate::effects::Reason) code per pixel) and, where an effect
//! changes z, its measured z; the sink reads both.

use crate::effects::{Effect, Effects, EFFECT_ORDER, MAX_NOISE_INCIDENCE_DEG};
use crate::error::Result;
use crate::gpu::shaders::layout::spec;
use crate::gpu::shaders::{matches_shader_bindings, matches_shader_struct};
use crate::gpu::{shaders, Buffer, ComputePipeline, GpuContext, Image, SetShape, StorageSet};
use crate::render::targets::ViewKind;
use crate::sensor::{PixelRect, Sensor, WitnessGeometry};
use ash::vk;
use std::sync::Arc;

/// Push constants of every effect pass; matches `Effect` in shaders/stages/effect.glsl.
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
pub struct EffectConstants {
    region: [u32; 4],
    width: u32,
    height: u32,
    use_shadowed: u32,
    z_in_buffer: u32,
    z_origin: f32,
    reference_kind: u32,
    witness_count: u32,
    /// The seed (noise, dropout) or the width in pixels (edges).
    seed_or_width: u32,
    params: [f32; 4],
    reflectivity_offset: u32,
    /// A fifth parameter (disparity's noise in pixels).
    param4: f32,
    witnesses: [u32; 2],
    reference_grid: [f32; 4],
}

matches_shader_struct!(
    EffectConstants,
    Effect {
        region,
        width,
        height,
        use_shadowed,
        z_in_buffer,
        z_origin,
        reference_kind,
        witness_count,
        seed_or_width,
        params,
        reflectivity_offset,
        param4,
        witnesses,
        reference_grid,
    }
);

/// Where a job's effect passes read and write, beyond the slot's images.
#[derive(Clone, Copy)]
pub(crate) struct EffectJob {
    pub region: PixelRect,
    pub size: (u32, u32),
    pub z_origin: f32,
    pub use_shadowed: bool,
    /// This job's label 0 in the reflectivity table.
    pub reflectivity_offset: u32,
}

impl EffectConstants {
    /// The constants of `effect`'s pass, which `effects` names; `z_in_buffer` says whether an
    /// earlier pass of the job changed z.
    fn new(effect: Effect, effects: &Effects, sensor: &EffectSensor, job: &EffectJob, z_in_buffer: bool) -> Self {
        let f = |v: f64| v as f32;
        let (seed_or_width, params) = match effect {
            Effect::Grazing => {
                let g = effects.grazing.expect("named");
                (0, [f(g.max_incidence_deg.to_radians().cos()), 0.0, 0.0, 0.0])
            }
            Effect::Range => {
                let r = effects.range.expect("named");
                (0, [f(r.min_z.unwrap_or(f64::NEG_INFINITY)), f(r.max_z.unwrap_or(f64::INFINITY)), 0.0, 0.0])
            }
            Effect::Reflectivity => (0, [f(effects.reflectivity.expect("named").threshold), 0.0, 0.0, 0.0]),
            Effect::Edges => {
                let e = effects.edges.expect("named");
                (e.width_px, [f(e.jump), 0.0, 0.0, 0.0])
            }
            Effect::Dropout => {
                let d = effects.dropout.expect("named");
                (d.seed, [f(d.probability), 0.0, 0.0, 0.0])
            }
            Effect::Noise => {
                let n = effects.noise.expect("named");
                (n.seed, [n.sigma, n.depth_coefficient, n.depth_reference, n.incidence_coefficient].map(f))
            }
            Effect::Quantize => (0, [f(effects.quantize.expect("named").z_step), 0.0, 0.0, 0.0]),
            Effect::Disparity => {
                let d = effects.disparity.expect("named");
                // Filled in from the sensor before any pass (`Effects::for_sensor`).
                let focal_baseline = d.baseline.zip(d.focal_px).map_or(f64::NAN, |(b, f)| b * f);
                (d.seed, [focal_baseline, d.subpixel, d.min_px, d.max_px].map(f))
            }
        };
        let param4 = effects.disparity.filter(|_| effect == Effect::Disparity).map_or(0.0, |d| f(d.noise_px));
        let r = job.region;
        Self {
            region: [r.col, r.row, r.width, r.height],
            width: job.size.0,
            height: job.size.1,
            use_shadowed: u32::from(job.use_shadowed),
            z_in_buffer: u32::from(z_in_buffer),
            z_origin: job.z_origin,
            reference_kind: sensor.reference_kind,
            witness_count: sensor.witness_count,
            seed_or_width,
            params,
            reflectivity_offset: job.reflectivity_offset,
            param4,
            witnesses: sensor.witnesses.address_words(),
            reference_grid: sensor.reference_grid,
        }
    }
}

/// The sensor as the effect passes measure against it (grazing and the noise's incidence
/// term): the reference view as shaders/common/view.glsl takes it, and a table on the device
/// of its witnesses in file order, each a unit direction toward it (w = 0) or its centre (w =
/// 1), in the reference frame. A scan's geometry, the same for every job of a submission.
pub(crate) struct EffectSensor {
    reference_kind: u32,
    reference_grid: [f32; 4],
    witnesses: Buffer,
    witness_count: u32,
}

impl EffectSensor {
    pub fn new(ctx: &Arc<GpuContext>, sensor: &Sensor) -> Result<Self> {
        let (reference_kind, grid) = sensor.reference.shader_view();
        let f = |v: f64| v as f32;
        let mut table: Vec<[f32; 4]> = sensor
            .witnesses
            .iter()
            .map(|witness| match witness.geometry {
                WitnessGeometry::Directional(direction) => {
                    let d = direction.vector();
                    [f(d.x), f(d.y), f(d.z), 0.0]
                }
                WitnessGeometry::Pinhole { pose, .. } => {
                    let centre = pose.w_axis;
                    [f(centre.x), f(centre.y), f(centre.z), 1.0]
                }
            })
            .collect();
        let witness_count = table.len() as u32;
        // A buffer is never empty; a sensor without witnesses reads none of it.
        if table.is_empty() {
            table.push([0.0; 4]);
        }
        let witnesses = Buffer::with_data(ctx, vk::BufferUsageFlags::STORAGE_BUFFER, &table, "effects' witnesses")?;
        Ok(Self { reference_kind, reference_grid: grid.map(f), witnesses, witness_count })
    }
}

/// The effect pipelines, one per effect, in [`EFFECT_ORDER`]; their set layouts are defined
/// identically, so one descriptor set serves them all.
pub struct EffectPipelines {
    pipelines: Vec<ComputePipeline>,
}

impl EffectPipelines {
    /// Storage images bound from binding 0: the range view's attachments.
    pub const IMAGES: usize = ViewKind::Range.colour_attachments().len();
    /// Storage buffers after them: shadowed labels, losses, measured z, reflectivities.
    pub const BUFFERS: usize = 4;

    pub fn new(ctx: &Arc<GpuContext>) -> Result<Self> {
        let max_incidence = (MAX_NOISE_INCIDENCE_DEG.to_radians() as f32).to_bits();
        let pipelines = EFFECT_ORDER
            .iter()
            .map(|&effect| {
                let (spirv, reason_id) = match effect {
                    Effect::Grazing => (shaders::EFFECT_GRAZING_COMP, spec::EFFECT_GRAZING_COMP::REASON),
                    Effect::Range => (shaders::EFFECT_WORKING_VOLUME_COMP, spec::EFFECT_WORKING_VOLUME_COMP::REASON),
                    Effect::Reflectivity => (shaders::EFFECT_REFLECTIVITY_COMP, spec::EFFECT_REFLECTIVITY_COMP::REASON),
                    Effect::Edges => (shaders::EFFECT_EDGES_COMP, spec::EFFECT_EDGES_COMP::REASON),
                    Effect::Dropout => (shaders::EFFECT_DROPOUT_COMP, spec::EFFECT_DROPOUT_COMP::REASON),
                    Effect::Noise => (shaders::EFFECT_NOISE_COMP, spec::EFFECT_NOISE_COMP::REASON),
                    Effect::Quantize => (shaders::EFFECT_QUANTIZE_COMP, spec::EFFECT_QUANTIZE_COMP::REASON),
                    Effect::Disparity => (shaders::EFFECT_DISPARITY_COMP, spec::EFFECT_DISPARITY_COMP::REASON),
                };
                let reason = effect.reason().map_or(0, |r| r.code());
                let mut constants = vec![(reason_id, reason)];
                if effect == Effect::Noise {
                    constants.push((spec::EFFECT_NOISE_COMP::MAX_INCIDENCE, max_incidence));
                }
                let name = format!("{} effect", effect.pass_name());
                ComputePipeline::new(
                    ctx,
                    SetShape::storage(Self::IMAGES, Self::BUFFERS),
                    size_of::<EffectConstants>(),
                    spirv,
                    &constants,
                    &name,
                )
            })
            .collect::<Result<_>>()?;
        Ok(Self { pipelines })
    }

    fn get(&self, effect: Effect) -> &ComputePipeline {
        let index = EFFECT_ORDER.iter().position(|&e| e == effect).expect("every effect has a pipeline");
        &self.pipelines[index]
    }

    pub fn set_layout(&self) -> vk::DescriptorSetLayout {
        self.pipelines[0].set_layout
    }
}

/// A slot's effect buffers and the descriptor set binding them with its range view.
pub(crate) struct EffectBuffers {
    /// Per pixel: the Reason code of the effect that lost it, 0 if none did.
    pub losses: Buffer,
    /// Per pixel: the measured z (range frame), where an effect changes z.
    pub measured_z: Option<Buffer>,
    set: StorageSet,
    /// Bound in place of buffers a slot does not have; never read then.
    _placeholder: Buffer,
}

/// How a slot's effect buffers are made.
pub(crate) struct EffectShape<'a> {
    pub changes_z: bool,
    pub reflectivities: Option<&'a Buffer>,
}

impl EffectBuffers {
    /// `desc(bytes)` makes a w·h-word buffer (host-visible for a readback slot).
    pub fn new(
        ctx: &Arc<GpuContext>,
        pipelines: &EffectPipelines,
        range_images: &[Image],
        shadowed_labels: Option<&Buffer>,
        shape: &EffectShape,
        desc: impl Fn() -> crate::gpu::BufferDesc,
        name: &str,
    ) -> Result<Self> {
        let losses = Buffer::new(ctx, desc(), &format!("{name} losses"))?;
        let measured_z =
            shape.changes_z.then(|| Buffer::new(ctx, desc(), &format!("{name} measured z"))).transpose()?;
        let placeholder = Buffer::new(ctx, crate::gpu::BufferDesc::gpu_storage(4), &format!("{name} placeholder"))?;
        let images: Vec<&Image> = range_images.iter().collect();
        let buffers = [
            shadowed_labels.unwrap_or(&placeholder),
            &losses,
            measured_z.as_ref().unwrap_or(&placeholder),
            shape.reflectivities.unwrap_or(&placeholder),
        ];
        matches_shader_bindings!([
            EFFECT_GRAZING_COMP,
            EFFECT_WORKING_VOLUME_COMP,
            EFFECT_REFLECTIVITY_COMP,
            EFFECT_EDGES_COMP,
            EFFECT_DROPOUT_COMP,
            EFFECT_NOISE_COMP,
            EFFECT_QUANTIZE_COMP,
        ] {
            range_label,
            range_z,
            range_dz_dx,
            range_dz_dy,
            ShadowedLabels,
            Losses,
            MeasuredZ,
            Reflectivities,
        });
        let set =
            StorageSet::new(ctx, pipelines.set_layout(), &images, (&[], &buffers), &format!("{name} effect bindings"))?;
        Ok(Self { losses, measured_z, set, _placeholder: placeholder })
    }

    /// Records `effect`'s pass (8×8 workgroups over the job's region).
    pub fn record(
        &self,
        cmd: vk::CommandBuffer,
        pipelines: &EffectPipelines,
        effect: Effect,
        (effects, sensor): (&Effects, &EffectSensor),
        job: &EffectJob,
        z_in_buffer: bool,
    ) {
        let constants = EffectConstants::new(effect, effects, sensor, job, z_in_buffer);
        let groups = [job.region.width, job.region.height].map(|n| n.div_ceil(8));
        self.set.dispatch(cmd, pipelines.get(effect), bytemuck::bytes_of(&constants), groups);
    }
}
