//! The compute pass that tests a pinhole reference view's points against every witness's
//! image (shaders/stages/witness_mask.comp), by the label test or the depth test (in two
//! passes: stages/walk_list.rs): what it reads of each witness, its push constants, and its
//! bindings. A job of one draw that the compute rasterizer drew is tested from the views'
//! visibility words, which no resolve pass turns into attachments first (`FROM_WORDS`, the
//! scanner's mask's way: stages/shadow_mask.rs).

use crate::error::Result;
use crate::exact::FACING_TOLERANCE;
use crate::gpu::shaders::{matches_shader_bindings, matches_shader_struct};
use crate::gpu::{Access, Buffer, BufferDesc, ComputePipeline, GpuContext, Image, StorageSet};
use crate::render::gpu_mesh::HullFaces;
use crate::render::stages::walk_list::WalkList;
use crate::render::targets::{ViewKind, ViewTargets};
use crate::sensor::{Intrinsics, PixelRect, MAX_WITNESSES};
use crate::shadow::{DEPTH_BIAS_PIXELS, DEPTH_BIAS_RELATIVE};
use ash::vk;
use glam::{DMat4, DVec3};
use std::sync::Arc;

/// One witness as the mask reads it (`WitnessData`, std430).
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
pub struct WitnessConstants {
    from_reference: [[f32; 4]; 3],
    centre: [f32; 4],
    grid: [f32; 4],
    band: [u32; 4],
    drawn: [u32; 4],
    draws: [u32; 2],
    _pad: [u32; 2],
}

matches_shader_struct!(WitnessConstants, WitnessData { from_reference, centre, grid, band, drawn, draws });

/// Which attachment a witness's band lies in: the pinhole witnesses' images, drawn in
/// projection, or the directional witnesses', drawn orthographically (each kind has its own
/// pipelines and depth order); `WitnessData.band.w`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum WitnessAttachment {
    Pinhole = 0,
    Directional = 1,
}

impl WitnessAttachment {
    pub const ALL: [WitnessAttachment; 2] = [WitnessAttachment::Pinhole, WitnessAttachment::Directional];
}

impl WitnessConstants {
    /// A pinhole witness whose pose is reference-from-witness, whose image has the
    /// `drawn` intrinsics (its `columns` applied) and lies in `band` of the pinhole witnesses'
    /// attachment. `None` where a value does not hold in f32.
    pub fn pinhole(pose: DMat4, drawn: &Intrinsics, band: PixelRect) -> Option<Self> {
        let constants = Self {
            from_reference: rows(pose.inverse()),
            centre: pose.w_axis.as_vec4().to_array(),
            grid: [drawn.fx, drawn.fy, drawn.cx, drawn.cy].map(|v| v as f32),
            band: [band.width, band.height, band.row, WitnessAttachment::Pinhole as u32],
            drawn: [0, 0, band.width, band.height],
            draws: [0; 2],
            _pad: [0; 2],
        };
        let mut floats = constants.from_reference.iter().flatten().chain(&constants.centre).chain(&constants.grid);
        floats.all(|v| v.is_finite()).then_some(constants)
    }

    /// A directional witness seen `toward` (unit, reference frame), turned to +z by the
    /// rotation `from_reference`, whose label image lies in `band` of the directional
    /// witnesses' attachment; its grid is each job's ([`WitnessConstants::with_grid`]).
    pub fn directional(from_reference: DMat4, toward: DVec3, band: PixelRect) -> Self {
        Self {
            from_reference: rows(from_reference),
            centre: toward.extend(0.0).as_vec4().to_array(),
            grid: [0.0; 4],
            band: [band.width, band.height, band.row, WitnessAttachment::Directional as u32],
            drawn: [0, 0, band.width, band.height],
            draws: [0; 2],
            _pad: [0; 2],
        }
    }

    /// The witness with its orthographic label image's grid (x0, y0, dx, dy: its band's first
    /// pixel's centre and the pitch) set: a directional witness's, planned for one job.
    pub fn with_grid(self, grid: [f64; 4]) -> Self {
        Self { grid: grid.map(|v| v as f32), ..self }
    }

    /// The witness with the pixels of its image a job draws, `area` of the attachment (the
    /// depth test reads no other, nor any test from the words), and its draw table for that
    /// job, which the depth test walks: at the device address `draws` (0 for the label tests).
    pub fn with_job(self, area: PixelRect, draws: u64) -> Self {
        let row = area.row.saturating_sub(self.band[2]);
        Self { drawn: [area.col, row, area.width, area.height], draws: [draws as u32, (draws >> 32) as u32], ..self }
    }
}

/// The first three rows of a transform, rounded once to f32.
fn rows(transform: DMat4) -> [[f32; 4]; 3] {
    let row = |i| transform.row(i).as_vec4().to_array();
    [row(0), row(1), row(2)]
}

/// The mask's push constants (`WitnessMask`, std430).
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
pub struct WitnessMaskConstants {
    intrinsics: [f32; 4],
    region: [u32; 4],
    strides: [u32; 4],
    width: u32,
    witness_count: u32,
    facing_tolerance: f32,
    bias_per_depth: f32,
    bias_relative: f32,
    hull_tolerance: f32,
    hull_faces: [u32; 2],
}

matches_shader_struct!(
    WitnessMaskConstants,
    WitnessMask {
        intrinsics,
        region,
        strides,
        width,
        witness_count,
        facing_tolerance,
        bias_per_depth,
        bias_relative,
        hull_tolerance,
        hull_faces
    }
);

impl WitnessMaskConstants {
    /// Tests the pixels of `region` of a reference view of intrinsics `reference` against the
    /// first `witness_count` witnesses of the slot's table.
    pub fn new(reference: &Intrinsics, region: PixelRect, witness_count: usize) -> Self {
        Self {
            intrinsics: [reference.fx, reference.fy, reference.cx, reference.cy].map(|v| v as f32),
            region: [region.col, region.row, region.width, region.height],
            strides: [0; 4],
            width: reference.width,
            witness_count: witness_count as u32,
            facing_tolerance: FACING_TOLERANCE as f32,
            // The depth test's constant bias: DEPTH_BIAS_PIXELS of a pixel's width at p's
            // depth, the finer axis's.
            bias_per_depth: (DEPTH_BIAS_PIXELS / reference.fx.max(reference.fy)) as f32,
            bias_relative: DEPTH_BIAS_RELATIVE as f32,
            hull_tolerance: 0.0,
            hull_faces: [0; 2],
        }
    }

    /// The same constants for a job of one draw that the compute rasterizer drew into `words`
    /// (the mask's `FROM_WORDS` pipelines), and in the depth test, of a mesh with hull faces
    /// (`GpuMesh::hull_faces`): the depth test then skips its walks from them, which nothing
    /// else in the views can hide.
    pub fn reading_words(self, words: &MaskWords, hull: Option<&HullFaces>) -> Self {
        let strides = [words.reference.1, words.witnesses[0].1, words.witnesses[1].1, 0];
        Self {
            strides,
            hull_faces: hull.map_or([0; 2], |hull| hull.bits.address_words()),
            hull_tolerance: hull.map_or(0.0, |hull| hull.tolerance),
            ..self
        }
    }
}

/// What the mask's `FROM_WORDS` pipelines read in place of the views' attachments
/// (raster/compute/rig.rs): the reference view's draw table, and the visibility words, with
/// their pixels a row, of the reference view and of the pinhole witnesses' attachment and the
/// directional witnesses' (where a rig has no witness of a kind, the other's, never read
/// there).
#[derive(Clone, Copy)]
pub(crate) struct MaskWords<'b> {
    pub reference_draws: &'b Buffer,
    pub reference: (&'b Buffer, u32),
    pub witnesses: [(&'b Buffer, u32); 2],
}

/// The slot's table of witnesses as the mask reads them (`WitnessTable`): each job writes its
/// own before its test ([`WitnessTable::record_writing`]), so that the mask reads it from a
/// binding of the slot's, which a software rasterizer reads at a fraction of the cost of a
/// table at a device address (docs/performance.md, "A pinhole rig beside the scanner").
pub(crate) struct WitnessTable {
    buffer: Buffer,
}

impl WitnessTable {
    pub fn new(ctx: &Arc<GpuContext>, name: &str) -> Result<Self> {
        let bytes = (MAX_WITNESSES * size_of::<WitnessConstants>()) as u64;
        Ok(Self { buffer: Buffer::new(ctx, BufferDesc::gpu_storage(bytes), &format!("{name} witness table"))? })
    }

    /// The use the step writing the table makes of it.
    pub fn written(&self) -> (&Buffer, Access) {
        (&self.buffer, Access::TransferWrite)
    }

    /// The use the mask's passes make of it.
    pub fn read(&self) -> (&Buffer, Access) {
        (&self.buffer, Access::ComputeRead)
    }

    /// Records the writing of a job's `witnesses`, which the mask's constants count (at most
    /// [`MAX_WITNESSES`], which `Sensor::validate` refuses beyond, as `WitnessLayout` does).
    pub fn record_writing(&self, ctx: &GpuContext, cmd: vk::CommandBuffer, witnesses: &[WitnessConstants]) {
        assert!(witnesses.len() <= MAX_WITNESSES, "a rig's witnesses were counted when it was read");
        if witnesses.is_empty() {
            return;
        }
        // SAFETY: cmd is recording; the step's barrier ordered earlier uses of the buffer; the
        // update fits the buffer (MAX_WITNESSES entries of 128 bytes: under 65,536).
        unsafe { ctx.device.cmd_update_buffer(cmd, self.buffer.raw, 0, bytemuck::cast_slice(witnesses)) };
    }
}

/// The mask's descriptor set: the reference view's attachments, the pinhole witnesses'
/// images and the directional witnesses', then the masked labels, each pixel's witness bits,
/// the depth test's walk list, what the `FROM_WORDS` pipelines read ([`MaskWords`]), and the
/// table of witnesses each job writes before its test ([`WitnessTable`]).
pub struct WitnessMaskBindings {
    set: StorageSet,
}

impl WitnessMaskBindings {
    pub const IMAGES: usize =
        ViewKind::Range.colour_attachments().len() + 2 * ViewKind::Shadow.colour_attachments().len();
    pub const BUFFERS: usize = 9;

    /// `pipeline`: any of the mask's pipelines (their set layouts are defined alike).
    /// `witnesses`: the pinhole witnesses' attachments and the directional witnesses' (where a
    /// rig has no witness of a kind, the other's, never read there). `words`: where the slot's
    /// jobs may be drawn by the compute rasterizer (else other buffers are bound in their
    /// place, never read).
    pub fn new(
        ctx: &Arc<GpuContext>,
        pipeline: &ComputePipeline,
        (reference, [pinhole, directional]): (&ViewTargets, [&ViewTargets; 2]),
        (masked, lost_by, walk_list): (&Buffer, &Buffer, &WalkList),
        words: Option<MaskWords>,
        table: &WitnessTable,
    ) -> Result<Self> {
        matches_shader_bindings!([
            WITNESS_MASK_COMP,
            WITNESS_MASK_WALKS_COMP,
            WITNESS_MASK_WORDS_COMP,
            WITNESS_MASK_WORDS_WALKS_COMP
        ] {
            range_label,
            range_z,
            range_dz_dx,
            range_dz_dy,
            witness_visibility,
            directional_visibility,
            Masked,
            LostBy,
            WalkArgs,
            WalkPixels,
            ReferenceDraws,
            ReferenceWords,
            PinholeWitnessWords,
            DirectionalWitnessWords,
            WitnessTable,
        });
        let images: Vec<&Image> = reference.colour.iter().chain(&pinhole.colour).chain(&directional.colour).collect();
        let from_words =
            words.map_or([masked; 4], |w| [w.reference_draws, w.reference.0, w.witnesses[0].0, w.witnesses[1].0]);
        let buffers = [
            masked,
            lost_by,
            &walk_list.args,
            &walk_list.pixels,
            from_words[0],
            from_words[1],
            from_words[2],
            from_words[3],
            &table.buffer,
        ];
        let set = StorageSet::new(ctx, pipeline.set_layout, &images, (&[], &buffers), "witness mask bindings")?;
        Ok(Self { set })
    }

    /// Records the test of `pipeline` over the constants' region (8×8 workgroups).
    pub fn record(&self, cmd: vk::CommandBuffer, pipeline: &ComputePipeline, constants: &WitnessMaskConstants) {
        let groups = [constants.region[2], constants.region[3]].map(|n| n.div_ceil(8));
        self.set.dispatch(cmd, pipeline, bytemuck::bytes_of(constants), groups);
    }

    /// Records the depth test's second pass, `walks`, over the pixels the first listed in
    /// `list`.
    pub fn record_walks(
        &self,
        cmd: vk::CommandBuffer,
        walks: &ComputePipeline,
        list: &WalkList,
        constants: &WitnessMaskConstants,
    ) {
        self.set.dispatch_indirect(cmd, walks, bytemuck::bytes_of(constants), &list.args);
    }
}
