//! The compute rasterizer (DESIGN.md "Raster paths"): a job's views rendered by compute passes
//! instead of the graphics pipeline, into the same attachments, so every pass after it is
//! unchanged.
//!
//! - Coverage (shaders/raster.comp), over the range view and the shadow view at once: one
//!   invocation per triangle reads its corners and normal once (reading them is most of a small
//!   triangle's set-up) and, in each view, finds the pixel centres it covers (1/256-pixel
//!   snapped corners, the top-left rule, exact integer edge functions in 32 bits) and keeps
//!   the nearest triangle per pixel with a 64-bit atomicMin of (depth bits, triangle) on that
//!   view's words, by tiles of 8 × 8 pixels. A triangle whose corners lie too far from its
//!   box for 32 bits (more than 32 pixels) is queued for that view instead, and a second,
//!   indirect dispatch gives each queued (triangle, view) a workgroup of 64 invocations, in
//!   64-bit arithmetic. Each view's draw reaches both as a uniform block, copied from its draw
//!   table before them. The coverage pass deals its workgroups over the mesh ([`DEAL_BLOCK`]),
//!   so that each thread of a software rasterizer gets a share of every part of it. Where the
//!   mesh bounds a solid (src/mesh/solid.rs), a
//!   triangle facing away from the camera in a view is skipped there, and one facing away in
//!   both is skipped before its corners are read.
//! - Resolve, the range view's: one invocation per pixel writes what the graphics path's
//!   fragment shader would have written for that triangle. Where a shadow mask follows, the
//!   mask does it as it tests each pixel, and reads the shadow view's words as they are
//!   (shadow_pass.rs): neither view takes a pass of its own. Without one, the resolve pass
//!   (shaders/raster_resolve.comp) does it.
//!
//! Triangle setup is where lavapipe's graphics pipeline spends its time (one thread, about
//! 0.2 µs a triangle), and a datacenter GPU runs its graphics pipeline on a few of its units;
//! a compute pass spreads the triangles over every core. So far it renders views of one draw
//! (every `verify` hypothesis, a scene of one object); a view of several draws keeps the
//! graphics path, whose tie rule the compute path does not implement yet, and so does a view
//! whose visibility words the device cannot bind as one storage buffer (Renderer::computes).
//!
//! [`Raster::Auto`], the default, picks per view: the compute rasterizer where the device has
//! it and the model has at least [`COMPUTE_CROSSOVER`] triangles per pixel of the footprint it
//! renders, the graphics pipeline elsewhere.

use super::draw::DrawConstants;
use super::shadow_pass::{MaskPipelines, MaskVariant, WordsToMask};
use super::targets::{ViewKind, ViewTargets};
use super::Draw;
use crate::error::Result;
use crate::gpu::{
    shaders, Access, Buffer, BufferDesc, ComputePipeline, Encoder, GpuContext, Image, SetShape, StorageSet,
};
use crate::mesh::Solidity;
use crate::sensor::PixelRect;
use ash::vk;
use std::sync::Arc;

/// Which rasterizer renders the views.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Raster {
    /// Per view: compute for dense models (see [`COMPUTE_CROSSOVER`]), else graphics.
    #[default]
    Auto,
    /// The graphics pipeline (the prescribed path).
    Graphics,
    /// The compute rasterizer, for views of one draw whose visibility words the device can
    /// bind; needs 64-bit buffer atomics.
    Compute,
}

/// Triangles per footprint pixel from which `auto` takes the compute rasterizer. Measured on
/// lavapipe with `bench_verify --rasters` (compute against graphics in the same run, batches
/// taken in turn; three runs, 2026-11-24): in depth-mode verification at 256², batches of 64,
/// the box, 0.001 triangles per footprint pixel, ran 1.00–1.12× as fast, spheres of 0.015
/// 1.35–1.43×, 0.071 1.39–1.48×, 0.17 1.56–1.68×, 0.31 1.63–1.81×, 0.70 1.90–2.07×, 1.3
/// 2.33–2.42×, 3.1 3.17–3.30×, 32 9.93–10.24×; the box filling a 256² image, 0.00018,
/// 1.05–1.22× in label mode and 1.05–1.23× in depth mode. Filling 512², 0.000046, it ran
/// 0.70–0.80× (label) and 0.90–0.95× (depth) as fast (two runs of batches of 16,
/// 2026-11-23). Compute starts to win between 0.000046 and 0.00018. No other device has been
/// measured yet; they use the same rule.
pub const COMPUTE_CROSSOVER: f64 = 0.0001;

impl Raster {
    pub fn as_str(self) -> &'static str {
        match self {
            Raster::Auto => "auto",
            Raster::Graphics => "graphics",
            Raster::Compute => "compute",
        }
    }

    /// Whether this choice renders a view of `draws` draws, with `triangles` triangles in all
    /// over a footprint of `footprint_pixels`, with the compute rasterizer, on a device that
    /// `has_compute` (64-bit buffer atomics) or not. `Compute` on a device without them is
    /// refused where its pipelines are built.
    pub fn computes(self, has_compute: bool, draws: usize, triangles: u64, footprint_pixels: u64) -> bool {
        match self {
            Raster::Graphics => false,
            Raster::Compute => draws == 1,
            Raster::Auto => {
                has_compute && draws == 1 && triangles as f64 >= COMPUTE_CROSSOVER * footprint_pixels as f64
            }
        }
    }
}

impl std::str::FromStr for Raster {
    type Err = String;

    fn from_str(text: &str) -> std::result::Result<Self, String> {
        match text {
            "auto" => Ok(Raster::Auto),
            "graphics" => Ok(Raster::Graphics),
            "compute" => Ok(Raster::Compute),
            other => Err(format!("unknown rasterizer {other:?}: expected auto, graphics or compute")),
        }
    }
}

/// One view as both passes see it; matches `RasterView` in shaders/raster_compute.glsl.
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct RasterView {
    area: [u32; 4],
    draw: u32,
    stride: u32,
    _pad: [u32; 2],
}

/// Push constants of the coverage passes; matches `Coverage` in shaders/raster.comp.
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct CoverageConstants {
    views: [RasterView; 2],
    triangles: u32,
    cull: i32,
    dealt_rows: u32,
}

const _: () = assert!(size_of::<RasterView>() == 32);
const _: () = assert!(std::mem::offset_of!(CoverageConstants, triangles) == 64);
const _: () = assert!(std::mem::offset_of!(CoverageConstants, cull) == 68);
const _: () = assert!(std::mem::offset_of!(CoverageConstants, dealt_rows) == 72);

/// `cull` of the coverage pass: which triangles it skips, by the sign of their view-frame
/// normal's z (the camera looks along −z). Only a solid's are skipped (src/mesh/solid.rs).
fn cull_sign(solidity: Solidity) -> i32 {
    match solidity {
        // Facing away: normal z < 0.
        Solidity::Outward => 1,
        Solidity::Inward => -1,
        Solidity::Open => 0,
    }
}

/// Bytes of a pixel's visibility word (shaders/visibility_word.glsl), in each view.
pub(crate) const VISIBILITY_WORD_BYTES: u64 = 8;
/// Bytes of the queue of large triangles for meshes of up to `triangles` in `views` views:
/// room for every triangle in every view, an entry (a triangle and its view's bit) 4 bytes.
pub(crate) fn large_queue_bytes(triangles: u64, views: u64) -> u64 {
    triangles.saturating_mul(views).saturating_mul(4)
}

/// Invocations per coverage workgroup (`local_size_x` in shaders/raster.comp).
const COVERAGE_GROUP: u32 = 64;
/// Coverage workgroups a block, and stripes of the mesh the blocks are dealt over (`main` in
/// shaders/raster.comp): each thread of a software rasterizer takes a share of every stripe,
/// from meshes of DEAL_BLOCK × DEAL_STRIPES × 2 workgroups (4,096 triangles). Measured on
/// lavapipe (2 threads; medians of four or five alternations), coverage of a UV sphere seen
/// along its poles, whose front half comes first in its file: 101,760 triangles at 256², 4.45
/// → 3.72 ms; at 1024², 22.0 → 14.6–16.7 ms; 9,800 triangles at 256², 1.30 → 1.09 ms. Seen
/// from the side, where its file's order already splits evenly: 3.29 → 3.33, 11.2 → 11.7–12.1
/// and 0.77 → 0.79 ms. Blocks of 8 workgroups were no better, nor worse at 1024².
const DEAL_BLOCK: u32 = 2;
const DEAL_STRIPES: u32 = 16;

/// Most workgroups along one dispatch dimension that every device allows: the coverage pass's
/// rows of workgroups, and the most the large triangles' indirect dispatch is given (the
/// shader's MAX_GROUPS, a specialization constant).
const MAX_GROUPS: u32 = 65_535;

pub struct ComputeRasterPipelines {
    /// The small triangles' coverage of the range view alone, and of both views.
    coverage_range: ComputePipeline,
    coverage_both: ComputePipeline,
    large: ComputePipeline,
    resolve: ComputePipeline,
    /// The shadow mask reading the shadow view's words (shadow_pass.rs), writing the range
    /// view's attachments whole, or only its z for a score pass.
    pub mask: MaskPipelines,
    pub mask_for_scoring: MaskPipelines,
}

impl ComputeRasterPipelines {
    pub fn new(ctx: &Arc<GpuContext>) -> Result<Self> {
        // Coverage binds both views' draws, then their visibility words, the large-triangle
        // queue and its dispatch arguments; resolve the range view's attachments, its table
        // and its words.
        let coverage = SetShape { images: 0, uniform_buffers: 1, storage_buffers: 4 };
        let coverage_push = size_of::<CoverageConstants>();
        // The coverage shader's specialization constants: MAX_GROUPS, the views it covers (the
        // large triangles' pass reads each queued triangle's view), and how it deals its
        // workgroups.
        let covering = |code, views: u32, name| {
            let constants = [MAX_GROUPS, views, DEAL_BLOCK, DEAL_STRIPES];
            ComputePipeline::new(ctx, coverage, coverage_push, code, &constants, name)
        };
        Ok(Self {
            coverage_range: covering(shaders::RASTER_COMP, 1, "compute raster coverage (range view)")?,
            coverage_both: covering(shaders::RASTER_COMP, 2, "compute raster coverage (both views)")?,
            large: covering(shaders::RASTER_LARGE_COMP, 2, "compute raster coverage (large triangles)")?,
            resolve: ComputePipeline::new(
                ctx,
                SetShape::storage(ViewKind::Range.colour_attachments().len(), 2),
                size_of::<RasterView>(),
                shaders::RASTER_RESOLVE_COMP,
                &[],
                "compute raster resolve",
            )?,
            mask: MaskPipelines::new(ctx, MaskVariant::Words)?,
            mask_for_scoring: MaskPipelines::new(ctx, MaskVariant::WordsForScoring)?,
        })
    }
}

/// A view the compute rasterizer renders: its attachments' size, and its draw table.
pub(crate) struct ComputeTarget<'a> {
    pub size: (u32, u32),
    pub draw_table: &'a Buffer,
}

/// One view's visibility words.
struct ViewWords<'a> {
    nearest: Buffer,
    /// Pixels per row of `nearest` (the attachments' width).
    stride: u32,
    draw_table: &'a Buffer,
}

/// The range view's and (where a shadow pass runs) the shadow view's visibility words, the
/// queue of large triangles the coverage pass fills for both, and the passes' bindings. The
/// range view's words are resolved into its attachments, by the shadow mask where there is a
/// shadow view and by the resolve pass where there is none; the shadow view's are read by the
/// shadow mask as they are.
pub(crate) struct ComputeViews<'a> {
    range: ViewWords<'a>,
    shadow: Option<ViewWords<'a>>,
    /// The queue of large (triangle, view) pairs, room for every triangle in every view, and
    /// its indirect dispatch's (x, y, z), then its length.
    large: Buffer,
    large_args: Buffer,
    /// The draw each view renders, copied from its draw table before each coverage pass.
    draws: Buffer,
    coverage: StorageSet,
    resolve: StorageSet,
}

impl<'a> ComputeViews<'a> {
    /// Visibility words for the views, rendering draws of no more than `max_triangles`, and
    /// the bindings that resolve the range view's into `range_targets`.
    pub fn new(
        ctx: &Arc<GpuContext>,
        pipelines: &ComputeRasterPipelines,
        (range, range_targets): (ComputeTarget<'a>, &ViewTargets),
        shadow: Option<ComputeTarget<'a>>,
        max_triangles: u32,
        name: &str,
    ) -> Result<Self> {
        let words = |kind: ViewKind, view: ComputeTarget<'a>| -> Result<ViewWords<'a>> {
            let (width, height) = view.size;
            let bytes = u64::from(width) * u64::from(height) * VISIBILITY_WORD_BYTES;
            let nearest =
                Buffer::new(ctx, BufferDesc::gpu_storage(bytes), &format!("{name} {kind:?} view visibility words"))?;
            Ok(ViewWords { nearest, stride: width, draw_table: view.draw_table })
        };
        let range = words(ViewKind::Range, range)?;
        let shadow = shadow.map(|view| words(ViewKind::Shadow, view)).transpose()?;
        let images: Vec<&Image> = range_targets.colour.iter().collect();
        let resolve = StorageSet::new(
            ctx,
            pipelines.resolve.set_layout,
            &images,
            (&[], &[range.draw_table, &range.nearest]),
            &format!("{name} resolve bindings"),
        )?;
        // A triangle is queued in a view at most once.
        let views = if shadow.is_some() { 2 } else { 1 };
        let large_bytes = large_queue_bytes(u64::from(max_triangles), views).max(4);
        let large = Buffer::new(ctx, BufferDesc::gpu_storage(large_bytes), &format!("{name} large triangles"))?;
        let args = BufferDesc {
            usage: BufferDesc::gpu_storage(0).usage | vk::BufferUsageFlags::INDIRECT_BUFFER,
            ..BufferDesc::gpu_storage(16)
        };
        let large_args = Buffer::new(ctx, args, &format!("{name} large-triangle dispatch"))?;
        let draws = BufferDesc {
            usage: vk::BufferUsageFlags::UNIFORM_BUFFER | vk::BufferUsageFlags::TRANSFER_DST,
            ..BufferDesc::gpu_storage(2 * size_of::<DrawConstants>() as u64)
        };
        let draws = Buffer::new(ctx, draws, &format!("{name} coverage draws"))?;
        // Without a shadow view, the range view's table and words fill its bindings too.
        let second = shadow.as_ref().unwrap_or(&range);
        let coverage = StorageSet::new(
            ctx,
            pipelines.coverage_both.set_layout,
            &[],
            (&[&draws], &[&range.nearest, &second.nearest, &large, &large_args]),
            &format!("{name} coverage bindings"),
        )?;
        Ok(Self { range, shadow, large, large_args, draws, coverage, resolve })
    }

    /// What the shadow mask's variant reading words reads (shadow_pass.rs), where these words
    /// include the shadow view's, and the views' pixels per row (range view's, shadow view's).
    pub fn to_mask(&self) -> Option<(WordsToMask<'_>, (u32, u32))> {
        self.shadow.as_ref().map(|shadow| {
            let words = WordsToMask {
                shadow_words: &shadow.nearest,
                range_table: self.range.draw_table,
                range_words: &self.range.nearest,
            };
            (words, (self.range.stride, shadow.stride))
        })
    }

    fn views(&self) -> impl Iterator<Item = &ViewWords<'a>> {
        std::iter::once(&self.range).chain(&self.shadow)
    }

    /// Records the passes of one draw (number `index` in the draw tables) over the range
    /// view's `range_area` and, where these words include the shadow view's, over its
    /// `shadow_area`. With a shadow view, both views' words are left for the shadow mask, which
    /// resolves the range view (shadow_pass.rs); without, the resolve pass writes the range
    /// view's colour attachments, in GENERAL layout as a compute pass leaves them.
    pub fn record(
        &self,
        enc: &mut Encoder,
        pipelines: &ComputeRasterPipelines,
        (range_targets, range_area): (&ViewTargets, PixelRect),
        shadow_area: Option<PixelRect>,
        (index, draw): (u32, &Draw),
    ) {
        let cmd = enc.cmd;
        // The rows of each view's area are emptied, not the whole view: a hypothesis costs its
        // footprint, not the image. Nothing reads a word beyond the area's rows, as nothing
        // reads the attachments beyond the area that the graphics pass clears (draw.rs).
        let emptied: Vec<_> = std::iter::once((&self.range, range_area))
            .chain(self.shadow.as_ref().zip(shadow_area))
            .map(|(view, area)| {
                let row_bytes = u64::from(view.stride) * VISIBILITY_WORD_BYTES;
                (view, u64::from(area.row) * row_bytes, u64::from(area.height) * row_bytes)
            })
            .collect();
        let mut cleared: Vec<_> = emptied.iter().map(|(view, ..)| (&view.nearest, Access::TransferWrite)).collect();
        cleared.extend([(&self.large_args, Access::TransferWrite), (&self.draws, Access::TransferWrite)]);
        cleared.extend(self.views().map(|view| (view.draw_table, Access::TransferRead)));
        enc.access(&[], &cleared);
        let entry = size_of::<DrawConstants>() as u64;
        // SAFETY: cmd is recording; the barrier above ordered earlier uses of the buffers; the
        // rows lie within the view's words, and their bytes are a multiple of 4.
        unsafe {
            let d = &enc.ctx().device;
            for &(view, offset, size) in &emptied {
                d.cmd_fill_buffer(cmd, view.nearest.raw, offset, size, u32::MAX);
            }
            // No workgroups, an empty queue: (x, y, z, length).
            d.cmd_update_buffer(cmd, self.large_args.raw, 0, bytemuck::cast_slice(&[0u32, 1, 1, 0]));
            // Each view's draw; without a shadow view, the second is loaded but never used.
            for (slot, view) in (0..).zip(self.views()) {
                let copy =
                    vk::BufferCopy { src_offset: u64::from(index) * entry, dst_offset: slot * entry, size: entry };
                d.cmd_copy_buffer(cmd, view.draw_table.raw, self.draws.raw, &[copy]);
            }
        }
        let raster_view = |view: &ViewWords, area: PixelRect| RasterView {
            area: [area.col, area.row, area.width, area.height],
            draw: index,
            stride: view.stride,
            _pad: [0; 2],
        };
        let range = raster_view(&self.range, range_area);
        let shadow = self.shadow.as_ref().zip(shadow_area).map(|(view, area)| raster_view(view, area));
        let triangles = draw.mesh.index_count / 3;
        let constants = CoverageConstants {
            views: [range, shadow.unwrap_or(range)],
            triangles,
            cull: cull_sign(draw.mesh.solidity),
            dealt_rows: triangles.div_ceil(COVERAGE_GROUP) / DEAL_BLOCK / DEAL_STRIPES,
        };
        let coverage_uses = |queue: Access, args: Access| {
            let mut uses: Vec<_> = self.views().map(|v| (&v.nearest, Access::ComputeWrite)).collect();
            uses.extend([(&self.large, queue), (&self.large_args, args), (&self.draws, Access::UniformRead)]);
            uses
        };
        enc.access(&[], &coverage_uses(Access::ComputeWrite, Access::ComputeWrite));
        let groups = triangles.div_ceil(COVERAGE_GROUP);
        let coverage_groups = [groups.min(MAX_GROUPS), groups.div_ceil(MAX_GROUPS)];
        let coverage = if shadow.is_some() { &pipelines.coverage_both } else { &pipelines.coverage_range };
        self.coverage.dispatch(cmd, coverage, bytemuck::bytes_of(&constants), coverage_groups);
        enc.access(&[], &coverage_uses(Access::ComputeRead, Access::IndirectAndComputeRead));
        self.coverage.dispatch_indirect(cmd, &pipelines.large, bytemuck::bytes_of(&constants), &self.large_args);
        if shadow.is_some() {
            return;
        }
        let writes: Vec<_> = range_targets.colour.iter().map(|image| (image, Access::ComputeWrite)).collect();
        enc.access(
            &writes,
            &[(&self.range.nearest, Access::ComputeRead), (self.range.draw_table, Access::ComputeRead)],
        );
        let pixels = [range_area.width, range_area.height].map(|n| n.div_ceil(8));
        self.resolve.dispatch(cmd, &pipelines.resolve, bytemuck::bytes_of(&range), pixels);
    }
}
