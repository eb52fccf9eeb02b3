//! The compute rasterizer (docs/design.md "Raster paths"): a job's views rendered by compute passes
//! instead of the graphics pipeline, into the same attachments, so every pass after it is
//! unchanged.
//!
//! - Coverage (shaders/raster/raster.comp), over the range view and the shadow view at once: one
//!   invocation per triangle reads its corners and normal once (reading them is most of a small
//!   triangle's set-up) and, in each view, finds the pixel centres it covers (1/256-pixel
//!   snapped corners, the top-left rule, exact integer edge functions in 32 bits) and keeps
//!   the nearest triangle per pixel with a 64-bit atomicMin of (key, triangle; tagged with its
//!   draw's place in a view of several draws, below) on that view's words, the key the exact z
//!   in the range view of one draw and the depth elsewhere (shaders/raster/visibility_word.glsl), by tiles
//!   of 8 × 8 pixels (one, in a variant without the tiles' code, which a software rasterizer
//!   would run whatever the boxes, where no triangle's box can be larger: `fits_one_tile`).
//!   A triangle whose corners lie too far from its box for 32 bits (more than 32 pixels) is
//!   queued for that view instead, and a second, indirect dispatch gives each queued
//!   (triangle, view) a workgroup of 64 invocations, in 64-bit arithmetic. Each view's draw
//!   reaches both in a uniform block, which the host writes before them. The coverage
//!   pass deals its workgroups over the mesh ([`DEAL_BLOCK`]), so that each thread of a
//!   software rasterizer gets a share of every part of it. Where the mesh bounds a solid
//!   (src/mesh/solid.rs), a triangle facing away from the camera in a view is skipped there,
//!   and one facing away in both is skipped before its corners are read.
//! - Many hypotheses a dispatch ([`CoverageGroup`]): the jobs of up to [`COVERAGE_MEMBERS`]
//!   consecutive slots of a batch are covered by one coverage dispatch (a z slice of workgroups
//!   each, their draws and constants in one uniform block, their words bound side by side) and
//!   one large triangles' dispatch, so that a GPU pays a dispatch and a barrier per group
//!   rather than per hypothesis. How many is the renderer's
//!   ([`Renderer::with_hypotheses_per_dispatch`](crate::render::Renderer::with_hypotheses_per_dispatch)):
//!   by default all of them on a GPU, and one on a CPU device, where a dispatch costs next to
//!   nothing and a group's reads of its members' constants cost more. Pipelines for one member
//!   are specialized to it (the member the constant 0), so a group of one runs the code a
//!   coverage pass of one job always ran. The images and counts are the same either way.
//!   Each group has buffers of its own, so a batch records all of a run of slots' groups side
//!   by side, one barrier a stage for them all (`Passes::record_coverage`).
//! - Resolve, the range view's (a view of one draw): one invocation per pixel writes what the
//!   graphics path's fragment shader would have written for that triangle. Where a shadow
//!   mask follows, the mask does it as it tests each pixel, and reads the shadow view's words
//!   as they are (stages/shadow_mask.rs): neither view takes a pass of its own. Without one, the
//!   resolve pass (shaders/raster/raster_resolve.comp) does it.
//! - Views of several draws (a scene of up to [`COVERAGE_MEMBERS`] objects,
//!   [`CoverageGroup::of_draws`]): the draws are the members of one coverage dispatch and
//!   share the view's words, each triangle tagged with its draw's place in the order the
//!   graphics path's ties pass draws them (draw.rs; `render` numbers its draws in that
//!   order). After the passes that keep the nearest, two ties passes (shaders/raster/raster.comp,
//!   TIES) keep, among the triangles within the tie depth of the nearest, the last drawn, as
//!   the graphics path's tie rule does (lavapipe: the same labels, shadowed labels and z bits,
//!   tests/compute_raster.rs). Resolve passes then write both views' attachments, and the
//!   shadow mask reads them as it reads the graphics path's.
//!
//! Triangle setup is where lavapipe's graphics pipeline spends its time (on one thread), and a
//! datacenter GPU runs its graphics pipeline on a few of its units; a compute pass spreads the
//! triangles over every core. A view of more draws than a dispatch's members keeps the graphics
//! path, and so does a view whose visibility words the device cannot bind as one storage
//! buffer, or whose draw reaches beyond [`MAX_REACH_PIXELS`] (Renderer::computes).
//!
//! Whether a view takes it is decided in raster_choice.rs ([`Raster`](crate::render::Raster),
//! [`Crossover`](crate::render::Crossover)).

use crate::error::Result;
use crate::gpu::shaders::{matches_shader_bindings, matches_shader_struct};
use crate::gpu::{shaders, Access, Buffer, BufferDesc, ComputePipeline, GpuContext, Image, SetShape, Step, StorageSet};
use crate::mesh::Solidity;
use crate::render::built_once::built_once;
use crate::render::raster::draw::{Draw, DrawConstants, DrawTable};
use crate::render::stages::shadow_mask::{MaskPipelines, MaskVariant, WordsToMask};
use crate::render::targets::{ViewKind, ViewTargets};
use crate::sensor::PixelRect;
use crate::shader_contract::{COVERAGE_GROUP, EMPTY_HALF, MEMBER_SHIFT, QUEUE_VIEW_BIT};
use ash::vk;
use std::sync::{Arc, OnceLock};

/// One view as both passes see it; matches `RasterView` in shaders/raster/raster_compute.glsl.
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct RasterView {
    area: [u32; 4],
    draw: u32,
    stride: u32,
    _pad: [u32; 2],
}

/// One member's constants in the coverage passes' uniform block; matches `Member` in
/// shaders/raster/raster.comp (std140: the same offsets, as it holds no vec3 and no array of scalars).
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct MemberConstants {
    views: [RasterView; 2],
    triangles: u32,
    cull: i32,
    dealt_rows: u32,
    /// Where the members share words (a view of several draws), the member's place in the
    /// ties order; else 0.
    place: u32,
    /// 1 where the member's range view is its own, of one draw: its words then hold z keys
    /// (shaders/raster/visibility_word.glsl), from which its resolve reads z; 0 where members share
    /// words, whose ties passes compare depths.
    z_keys: u32,
    _pad: [u32; 3],
}

matches_shader_struct!(RasterView, RasterView { area, draw, stride });
matches_shader_struct!(MemberConstants, Member { views, triangles, cull, dealt_rows, place, z_keys });

/// The coverage passes' uniform block; matches `Coverage` in shaders/raster/raster.comp (std140: the
/// same offsets, as DrawData and Member keep them and their sizes are multiples of 16). Each
/// member's draw in each view: draws[m] its range view's, draws[COVERAGE_MEMBERS + m] its
/// shadow view's; then each member's constants.
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct CoverageUniforms {
    draws: [DrawConstants; 2 * COVERAGE_MEMBERS],
    members: [MemberConstants; COVERAGE_MEMBERS],
}

matches_shader_struct!(CoverageUniforms, Coverage { draws, members });

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

/// Bytes of a pixel's visibility word (shaders/raster/visibility_word.glsl), in each view.
pub(crate) const VISIBILITY_WORD_BYTES: u64 = 8;
/// Bytes of the queue of large triangles for meshes of up to `triangles` in `views` views:
/// room for every triangle in every view, an entry (a triangle and its view's bit) 4 bytes.
pub(crate) fn large_queue_bytes(triangles: u64, views: u64) -> u64 {
    triangles.saturating_mul(views).saturating_mul(4)
}

/// How far from a view's first pixel, in pixels, a draw's corners may lie for the compute
/// rasterizer to render it (`Renderer::computes`; beyond, the graphics pipeline does): 2^21.
/// Snapped to 1/256 pixel, the corners lie within 2^29 + 128 units of a box's first pixel
/// centre, their differences within 2^30 + 256, and the large triangles' 64-bit edge
/// functions below 2^62, exact; farther, they overflowed (and corners
/// beyond 2^31 pixels did not convert to integers at all), and a triangle reaching millions of
/// pixels past the view went missing.
pub const MAX_REACH_PIXELS: f64 = 2_097_152.0;

/// Coverage workgroups a block, and stripes of the mesh the blocks are dealt over (`main` in
/// shaders/raster/raster.comp): each thread of a software rasterizer takes a share of every stripe,
/// from meshes of DEAL_BLOCK × DEAL_STRIPES × 2 workgroups (4,096 triangles). On lavapipe this
/// speeds the coverage of a mesh whose file lists the half in view first (a UV sphere seen
/// along its poles), and costs little where the file's order already splits evenly. Blocks of
/// 8 workgroups are no better.
const DEAL_BLOCK: u32 = 2;
const DEAL_STRIPES: u32 = 16;

/// Most workgroups along one dispatch dimension that every device allows: the coverage pass's
/// rows of workgroups, and the most the large triangles' indirect dispatch is given (the
/// shader's MAX_GROUPS, a specialization constant).
const MAX_GROUPS: u32 = 65_535;

pub use crate::shader_contract::COVERAGE_MEMBERS;

// A member's place (below COVERAGE_MEMBERS) goes above a triangle's index in the words and in
// the queue of large triangles, from bit MEMBER_SHIFT, below the queue's view bit: both fit
// only while meshes have fewer than 2^MEMBER_SHIFT triangles.
const _: () = assert!(
    crate::mesh::MAX_LINKED_TRIANGLES <= 1 << MEMBER_SHIFT
        && COVERAGE_MEMBERS <= 1 << (QUEUE_VIEW_BIT - MEMBER_SHIFT)
        && COVERAGE_MEMBERS.is_power_of_two()
);

/// Storage buffers the coverage passes bind: each member's words in each view, the queue of
/// large triangles and its dispatch arguments (a device binding fewer a stage cannot run the
/// compute rasterizer; Vulkan guarantees 4, the GPUs it targets bind thousands).
pub const COVERAGE_STORAGE_BUFFERS: usize = 2 * COVERAGE_MEMBERS + 2;

/// Whether `ctx`'s device can run the compute rasterizer: 64-bit integers and buffer atomics,
/// and as many storage buffers a shader stage as its coverage pass binds.
pub fn device_supports(ctx: &GpuContext) -> bool {
    ctx.has_int64_atomics() && ctx.max_storage_buffers_per_stage() >= COVERAGE_STORAGE_BUFFERS
}

/// The coverage passes' pipelines for dispatches of `members` jobs, or (`Ties`) the passes
/// after them that decide the ties between draws sharing words.
struct CoveragePipelines {
    /// The small triangles' coverage, covering boxes over a tile by tiles; and without the
    /// tiles' code, for meshes whose every triangle fits one tile (`fits_one_tile`), built on
    /// first use.
    tiled: SmallTriangles,
    one_tile: OnceLock<SmallTriangles>,
    large: ComputePipeline,
    ctx: Arc<GpuContext>,
    members: u32,
    kind: Coverage,
}

/// The small triangles' coverage of the range view alone, and of both views.
struct SmallTriangles {
    range: ComputePipeline,
    both: ComputePipeline,
}

/// Whether every triangle of a mesh whose longest edge is `longest_edge` (model units) has a
/// box of at most 8 pixels a side (one tile) in views of pixels `pitch` or larger: its
/// projection spans at most that edge, and a span of `w` pixels from `lo` has its box's pixel
/// centres from floor(`lo` − ½) to ceil(`lo` + `w` − ½), at most ceil(`w`) + 2 of them, so 5.9
/// pixels (below 6, for the rounding of poses and corners) leaves at most 8. The small
/// triangles' pass then leaves out the tiles' code, which a software rasterizer runs whatever
/// the boxes, so dense meshes cover faster there.
fn fits_one_tile(longest_edge: f64, pitch: f64) -> bool {
    longest_edge <= 5.9 * pitch
}

/// Which of shaders/raster/raster.comp's two kinds of coverage passes.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Coverage {
    /// The nearest triangle a pixel.
    Nearest,
    /// Among the triangles within the tie depth of the nearest, the last drawn (TIES).
    Ties,
}

impl CoveragePipelines {
    fn new(ctx: &Arc<GpuContext>, members: u32, kind: Coverage) -> Result<Self> {
        let large = match kind {
            Coverage::Nearest => shaders::RASTER_LARGE_COMP,
            Coverage::Ties => shaders::RASTER_LARGE_TIES_COMP,
        };
        Ok(Self {
            tiled: SmallTriangles::new(ctx, members, kind, true)?,
            one_tile: OnceLock::new(),
            large: covering(ctx, (members, kind), large, (2, true), "compute raster coverage (large triangles)")?,
            ctx: ctx.clone(),
            members,
            kind,
        })
    }

    /// The small triangles' pipelines, with the tiles' code or (`one_tile`) without.
    fn small(&self, one_tile: bool) -> Result<&SmallTriangles> {
        if !one_tile {
            return Ok(&self.tiled);
        }
        built_once(&self.one_tile, || SmallTriangles::new(&self.ctx, self.members, self.kind, false))
    }
}

impl SmallTriangles {
    fn new(ctx: &Arc<GpuContext>, members: u32, kind: Coverage, tiles: bool) -> Result<Self> {
        let code = match kind {
            Coverage::Nearest => shaders::RASTER_COMP,
            Coverage::Ties => shaders::RASTER_TIES_COMP,
        };
        let name = |view: &str| {
            let tiles = if tiles { "" } else { ", one tile" };
            format!("compute raster coverage ({view}{tiles})")
        };
        Ok(Self {
            range: covering(ctx, (members, kind), code, (1, tiles), &name("range view"))?,
            both: covering(ctx, (members, kind), code, (2, tiles), &name("both views"))?,
        })
    }
}

/// A coverage pipeline of shaders/raster/raster.comp's variant `code`, for dispatches of `members`
/// jobs of `kind`, covering `views` (the range view, or both; the large triangles' pass reads
/// each queued triangle's view), boxes over a tile by tiles or not.
fn covering(
    ctx: &Arc<GpuContext>,
    (members, kind): (u32, Coverage),
    code: &[u8],
    (views, tiles): (u32, bool),
    name: &str,
) -> Result<ComputePipeline> {
    // The uniform block (the members' draws and constants), each member's words in each view,
    // the large-triangle queue and its dispatch arguments.
    let shape = SetShape { images: 0, uniform_buffers: 1, storage_buffers: COVERAGE_STORAGE_BUFFERS };
    // The shader's specialization constants: MAX_GROUPS, the views it covers, how it deals its
    // workgroups, whether a dispatch covers one job or up to COVERAGE_MEMBERS, and TILES.
    use shaders::layout::spec::RASTER_COMP as spec;
    let constants = [
        (spec::MAX_GROUPS, MAX_GROUPS),
        (spec::VIEW_COUNT, views),
        (spec::DEAL_BLOCK, DEAL_BLOCK),
        (spec::DEAL_STRIPES, DEAL_STRIPES),
        (spec::MEMBERS, members),
        (spec::TILES, u32::from(tiles)),
    ];
    let dispatch = match (kind, members) {
        (Coverage::Ties, _) => "ties",
        (Coverage::Nearest, 1) => "one job",
        (Coverage::Nearest, _) => "grouped",
    };
    ComputePipeline::new(ctx, shape, 0, code, &constants, &format!("{name}, {dispatch}"))
}

pub struct ComputeRasterPipelines {
    ctx: Arc<GpuContext>,
    /// Coverage a job a dispatch; coverage of several, and the ties passes of a view of
    /// several draws, built on first use.
    single: CoveragePipelines,
    grouped: OnceLock<CoveragePipelines>,
    ties: OnceLock<CoveragePipelines>,
    /// The range view's resolve where its words hold one draw, and where they hold several;
    /// the shadow view's where they hold several.
    resolve: ComputePipeline,
    resolve_several: ComputePipeline,
    resolve_shadow: ComputePipeline,
    /// The shadow mask reading the shadow view's words (stages/shadow_mask.rs), writing the range
    /// view's attachments whole, or only its z for a score pass.
    pub mask: MaskPipelines,
    pub mask_for_scoring: MaskPipelines,
}

impl ComputeRasterPipelines {
    pub fn new(ctx: &Arc<GpuContext>) -> Result<Self> {
        // A view's attachments, its table and its words; whether the words hold several draws.
        let resolve = |kind: ViewKind, code, several: bool, name: &str| {
            let shape = SetShape::storage(kind.colour_attachments().len(), 2);
            let several = (shaders::layout::spec::RASTER_RESOLVE_COMP::SEVERAL_DRAWS, u32::from(several));
            ComputePipeline::new(ctx, shape, size_of::<RasterView>(), code, &[several], name)
        };
        Ok(Self {
            ctx: ctx.clone(),
            single: CoveragePipelines::new(ctx, 1, Coverage::Nearest)?,
            grouped: OnceLock::new(),
            ties: OnceLock::new(),
            resolve: resolve(ViewKind::Range, shaders::RASTER_RESOLVE_COMP, false, "compute raster resolve")?,
            resolve_several: resolve(
                ViewKind::Range,
                shaders::RASTER_RESOLVE_COMP,
                true,
                "compute raster resolve (several draws)",
            )?,
            resolve_shadow: resolve(
                ViewKind::Shadow,
                shaders::RASTER_RESOLVE_SHADOW_COMP,
                true,
                "compute raster resolve (shadow view, several draws)",
            )?,
            mask: MaskPipelines::new(ctx, MaskVariant::Words)?,
            mask_for_scoring: MaskPipelines::new(ctx, MaskVariant::WordsForScoring)?,
        })
    }

    /// The coverage pipelines for dispatches of `members` jobs (1 to [`COVERAGE_MEMBERS`]): one
    /// job's, or the grouped ones, which cover up to [`COVERAGE_MEMBERS`].
    fn coverage(&self, members: usize) -> Result<&CoveragePipelines> {
        if members == 1 {
            return Ok(&self.single);
        }
        self.built(&self.grouped, Coverage::Nearest)
    }

    /// The grouped pipelines of `kind`, in `cell`, built on first use.
    fn built<'s>(&self, cell: &'s OnceLock<CoveragePipelines>, kind: Coverage) -> Result<&'s CoveragePipelines> {
        built_once(cell, || CoveragePipelines::new(&self.ctx, COVERAGE_MEMBERS as u32, kind))
    }
}

/// A view the compute rasterizer renders: its attachments' size, and its draw table.
pub(crate) struct ComputeTarget<'a> {
    pub size: (u32, u32),
    pub draw_table: &'a DrawTable,
}

/// One view's visibility words.
struct ViewWords<'a> {
    nearest: Buffer,
    /// Pixels per row of `nearest` (the attachments' width).
    stride: u32,
    draw_table: &'a DrawTable,
}

/// One slot's visibility words: the range view's and (where a shadow pass runs) the shadow
/// view's, which a [`CoverageGroup`] fills, and the bindings that resolve each view's. Where
/// they hold one draw, the range view's words are resolved into its attachments, by the
/// shadow mask where there is a shadow view and by the resolve pass where there is none, and
/// the shadow view's are read by the shadow mask as they are. Where they hold several, the
/// resolve passes write both views' attachments, which the shadow mask then reads as the
/// graphics path leaves them.
pub(crate) struct ComputeViews<'a> {
    range: ViewWords<'a>,
    shadow: Option<ViewWords<'a>>,
    resolve: StorageSet,
    resolve_shadow: Option<StorageSet>,
}

impl<'a> ComputeViews<'a> {
    /// Visibility words for the views, and the bindings that resolve the range view's into
    /// `range_targets`, and where they hold `several_draws`, the shadow view's into its targets.
    pub fn new(
        ctx: &Arc<GpuContext>,
        pipelines: &ComputeRasterPipelines,
        (range, range_targets): (ComputeTarget<'a>, &ViewTargets),
        shadow: Option<(ComputeTarget<'a>, &ViewTargets)>,
        several_draws: bool,
        name: &str,
    ) -> Result<Self> {
        let words = |kind: ViewKind, view: ComputeTarget<'a>| -> Result<ViewWords<'a>> {
            let (width, height) = view.size;
            let bytes = u64::from(width) * u64::from(height) * VISIBILITY_WORD_BYTES;
            let nearest =
                Buffer::new(ctx, BufferDesc::gpu_storage(bytes), &format!("{name} {kind:?} view visibility words"))?;
            Ok(ViewWords { nearest, stride: width, draw_table: view.draw_table })
        };
        matches_shader_bindings!([RASTER_RESOLVE_COMP] { label, z, dz_dx, dz_dy, DrawTable, Nearest });
        matches_shader_bindings!([RASTER_RESOLVE_SHADOW_COMP] { visibility, DrawTable, Nearest });
        let resolve_set = |pipeline: &ComputePipeline, targets: &ViewTargets, words: &ViewWords, kind: ViewKind| {
            let images: Vec<&Image> = targets.colour.iter().collect();
            let buffers = [&words.draw_table.buffer, &words.nearest];
            StorageSet::new(ctx, pipeline.set_layout, &images, (&[], &buffers), &format!("{name} {kind:?} resolve"))
        };
        let range = words(ViewKind::Range, range)?;
        let resolve = resolve_set(&pipelines.resolve, range_targets, &range, ViewKind::Range)?;
        let (shadow, resolve_shadow) = match shadow {
            Some((view, targets)) => {
                let shadow = words(ViewKind::Shadow, view)?;
                let set = several_draws
                    .then(|| resolve_set(&pipelines.resolve_shadow, targets, &shadow, ViewKind::Shadow))
                    .transpose()?;
                (Some(shadow), set)
            }
            None => (None, None),
        };
        Ok(Self { range, shadow, resolve, resolve_shadow })
    }

    /// What the shadow mask's variant reading words reads (stages/shadow_mask.rs), where these words
    /// include the shadow view's, and the views' pixels per row (range view's, shadow view's).
    pub fn to_mask(&self) -> Option<(WordsToMask<'_>, (u32, u32))> {
        self.shadow.as_ref().map(|shadow| {
            let words = WordsToMask {
                shadow_words: &shadow.nearest,
                range_table: &self.range.draw_table.buffer,
                range_words: &self.range.nearest,
            };
            (words, (self.range.stride, shadow.stride))
        })
    }

    fn views(&self) -> impl Iterator<Item = &ViewWords<'a>> {
        std::iter::once(&self.range).chain(&self.shadow)
    }

    fn raster_view(view: &ViewWords, area: PixelRect, draw: u32) -> RasterView {
        RasterView { area: [area.col, area.row, area.width, area.height], draw, stride: view.stride, _pad: [0; 2] }
    }

    /// The resolve pass of the range view's words over `area` into `targets`, its colour
    /// attachments, which it leaves in GENERAL layout as a compute pass does. The words hold
    /// `draws` draws, from number `first` in the draw table. Words of one draw are resolved
    /// this way only where no shadow mask follows to resolve them.
    pub fn resolve_step<'s>(
        &'s self,
        pipelines: &'s ComputeRasterPipelines,
        area_in: (&'s ViewTargets, PixelRect),
        (first, draws): (u32, usize),
    ) -> Step<'s> {
        let pipeline = if draws == 1 { &pipelines.resolve } else { &pipelines.resolve_several };
        Self::resolving(&self.range, &self.resolve, pipeline, area_in, first)
    }

    /// The shadow view's resolve pass, as [`ComputeViews::resolve_step`], where its words hold
    /// several draws (the shadow mask reads one draw's as they are); none where these words
    /// have no shadow view or were made for one draw.
    pub fn resolve_shadow_step<'s>(
        &'s self,
        pipelines: &'s ComputeRasterPipelines,
        area_in: (&'s ViewTargets, PixelRect),
        first: u32,
    ) -> Option<Step<'s>> {
        let (words, set) = self.shadow.as_ref().zip(self.resolve_shadow.as_ref())?;
        Some(Self::resolving(words, set, &pipelines.resolve_shadow, area_in, first))
    }

    fn resolving<'s>(
        words: &'s ViewWords,
        set: &'s StorageSet,
        pipeline: &'s ComputePipeline,
        (targets, area): (&'s ViewTargets, PixelRect),
        first: u32,
    ) -> Step<'s> {
        let writes: Vec<_> = targets.colour.iter().map(|image| (image, Access::ComputeWrite)).collect();
        let reads = vec![(&words.nearest, Access::ComputeRead), (&words.draw_table.buffer, Access::ComputeRead)];
        let pixels = [area.width, area.height].map(|n| n.div_ceil(8));
        let view = Self::raster_view(words, area, first);
        Step::new(writes, reads, move |_, cmd| set.dispatch(cmd, pipeline, bytemuck::bytes_of(&view), pixels))
    }
}

/// One job of a coverage dispatch: its slot's words, the areas of its views to cover (the
/// shadow view's where a shadow pass runs), and its draw (number `index` in the draw tables).
pub(crate) struct CoverageMember<'v, 'a> {
    pub views: &'v ComputeViews<'a>,
    pub range_area: PixelRect,
    pub shadow_area: Option<PixelRect>,
    pub index: u32,
    pub draw: &'v Draw<'v>,
    /// The finest pixel pitch of the views it covers, in model units.
    pub finest_pitch: f64,
}

/// The coverage passes of a submission's slots: jobs in consecutive slots share a dispatch,
/// up to `members` of them (the slots in runs of `members`). Each run has its own bindings of
/// its slots' words, queue of large triangles, draws and members' constants, so that a batch
/// may record every run's coverage side by side (`Passes::record_coverage`); each is reused
/// by the run's slots' next jobs.
///
/// Or the coverage of one job's several draws (a view of several objects), its members,
/// which share its words: the passes that keep the nearest, then the ties passes, which keep
/// the one the graphics path's ties rule keeps ([`CoverageGroup::of_draws`]).
pub(crate) struct CoverageGroup {
    members: usize,
    runs: Vec<CoverageRun>,
    shared_words: bool,
}

/// What one run of slots' coverage dispatches use.
struct CoverageRun {
    /// The queue of large (triangle, member, view) entries, room for every triangle of every
    /// member in every view, and its indirect dispatch's (x, y, z), then its length.
    large: Buffer,
    large_args: Buffer,
    /// The members' draws and constants ([`CoverageUniforms`]), written before each coverage
    /// pass.
    uniforms: Buffer,
    set: StorageSet,
}

impl CoverageGroup {
    /// The coverage of `slots` (their words, in slot order), up to `members` slots a dispatch
    /// (1 to [`COVERAGE_MEMBERS`]; fewer where a queue of large triangles with room for every
    /// triangle of every member would be more than the device binds), rendering draws of no
    /// more than `max_triangles`.
    pub fn new(
        ctx: &Arc<GpuContext>,
        pipelines: &ComputeRasterPipelines,
        slots: &[&ComputeViews],
        members: usize,
        max_triangles: u32,
    ) -> Result<Self> {
        assert!((1..=COVERAGE_MEMBERS).contains(&members), "1 to {COVERAGE_MEMBERS} jobs a coverage dispatch");
        // A triangle is queued in a view of a member at most once. One member's queue always
        // fits: a view whose queue would not stays on the graphics path (Renderer::computes).
        let views = if slots.iter().any(|s| s.shadow.is_some()) { 2 } else { 1 };
        let member_bytes = large_queue_bytes(u64::from(max_triangles), views).max(1);
        let fitting = usize::try_from(ctx.max_storage_buffer_range() / member_bytes).unwrap_or(usize::MAX);
        let members = members.min(fitting).max(1);
        let layout = pipelines.coverage(members)?.tiled.both.set_layout;
        let runs = slots
            .chunks(members)
            .enumerate()
            .map(|(run, slots)| CoverageRun::new(ctx, layout, slots, member_bytes * members as u64, run))
            .collect::<Result<_>>()?;
        Ok(Self { members, runs, shared_words: false })
    }

    /// The coverage of one job of `draws` draws (2 to [`COVERAGE_MEMBERS`]) into `views`, in
    /// one dispatch, the draws of up to `max_triangles` each; refused where its queue of large
    /// triangles would be more than the device binds (`Renderer::computes` leaves such a view
    /// to the graphics pipeline).
    pub fn of_draws(
        ctx: &Arc<GpuContext>,
        pipelines: &ComputeRasterPipelines,
        views: &ComputeViews,
        draws: usize,
        max_triangles: u32,
    ) -> Result<Self> {
        assert!((2..=COVERAGE_MEMBERS).contains(&draws), "2 to {COVERAGE_MEMBERS} draws share a view's words");
        let group = Self::new(ctx, pipelines, &vec![views; draws], draws, max_triangles)?;
        if group.members < draws {
            return Err(crate::error::Error::Unsupported(format!(
                "the compute rasterizer's queue of large triangles for {draws} draws of up to {max_triangles} \
                 triangles is more than this device binds in one buffer"
            )));
        }
        Ok(Self { shared_words: true, ..group })
    }

    /// Jobs a coverage dispatch covers.
    pub fn members(&self) -> usize {
        self.members
    }

    /// The coverage passes of one run of slots (number `run`), `members[m]` the job of its
    /// slot m, where the compute rasterizer renders it: three steps, the run's words and
    /// buffers made ready, the coverage dispatch and the large triangles' (none where no
    /// member is covered); for one job's draws, `members[m]` its draw m, and two more, the
    /// ties passes'. Both views' words are left for the shadow mask, which resolves the
    /// range view (stages/shadow_mask.rs), or for the resolve pass where there is no shadow view
    /// ([`ComputeViews::resolve_step`]).
    pub fn steps<'s>(
        &'s self,
        pipelines: &'s ComputeRasterPipelines,
        run: usize,
        members: &[Option<CoverageMember<'s, '_>>],
    ) -> Result<Vec<Step<'s>>> {
        let covered: Vec<(usize, &CoverageMember)> =
            members.iter().enumerate().filter_map(|(m, member)| Some((m, member.as_ref()?))).collect();
        // A member's place is its index: one job's draws come in the ties order (the lowest
        // label last, as `render` numbers them), as the ties passes and the resolve read them.
        debug_assert!(
            !self.shared_words || covered.windows(2).all(|pair| pair[0].1.draw.label_base >= pair[1].1.draw.label_base),
            "a view's draws come in the ties order"
        );
        if covered.is_empty() {
            return Ok(Vec::new());
        }
        let coverage = pipelines.coverage(self.members)?;
        let buffers = &self.runs[run];
        // Each view's words, where the job covers it: the rows of its area are emptied, not
        // the whole view: a hypothesis costs its footprint, not the image. Nothing reads a
        // word beyond the area's rows, as nothing reads the attachments beyond the area that
        // the graphics pass clears (draw.rs).
        let mut emptied: Vec<(&'s Buffer, u64, u64)> = Vec::new();
        // One job's draws share its words and areas: the first's are all of them.
        let emptying = if self.shared_words { &covered[..1] } else { &covered[..] };
        for (_, member) in emptying {
            let shadow = member.views.shadow.as_ref().zip(member.shadow_area);
            for (view, area) in std::iter::once((&member.views.range, member.range_area)).chain(shadow) {
                let row_bytes = u64::from(view.stride) * VISIBILITY_WORD_BYTES;
                emptied.push((&view.nearest, u64::from(area.row) * row_bytes, u64::from(area.height) * row_bytes));
            }
        }
        let covered_words: Vec<&'s Buffer> = emptied.iter().map(|&(words, ..)| words).collect();
        // Only the covered members' words are declared: the others bound beside them (a
        // graphics job's slot, slots past a short run's end) are never touched, their members
        // covering no triangles.
        let mut cleared: Vec<_> = emptied.iter().map(|&(words, ..)| (words, Access::TransferWrite)).collect();
        cleared.extend([&buffers.large_args, &buffers.uniforms].map(|b| (b, Access::TransferWrite)));
        // The members' draws and constants, written in one command rather than an update and
        // two copies from the draw tables: on a GPU each command costs time of its own.
        let mut uniforms = <CoverageUniforms as bytemuck::Zeroable>::zeroed();
        for &(m, member) in &covered {
            let range = ComputeViews::raster_view(&member.views.range, member.range_area, member.index);
            let shadow = member.views.shadow.as_ref().zip(member.shadow_area);
            let triangles = member.draw.mesh.index_count / 3;
            // A member without a shadow view, in a dispatch covering others' (no batch has
            // one today: the mode and θ decide for all its jobs), covers no pixels there.
            let no_shadow = RasterView { area: [0; 4], ..range };
            uniforms.members[m] = MemberConstants {
                views: [
                    range,
                    shadow.map_or(no_shadow, |(view, area)| ComputeViews::raster_view(view, area, member.index)),
                ],
                triangles,
                cull: cull_sign(member.draw.mesh.solidity),
                dealt_rows: triangles.div_ceil(COVERAGE_GROUP) / DEAL_BLOCK / DEAL_STRIPES,
                place: if self.shared_words { m as u32 } else { 0 },
                z_keys: u32::from(!self.shared_words),
                _pad: [0; 3],
            };
            for (slot, view) in [m, COVERAGE_MEMBERS + m].into_iter().zip(member.views.views()) {
                uniforms.draws[slot] = view.draw_table.entries[member.index as usize];
            }
        }
        let prepare = move |ctx: &GpuContext, cmd| {
            let d = &ctx.device;
            // SAFETY: cmd is recording; the step's barrier ordered earlier uses of the buffers;
            // the rows lie within the views' words, and their bytes are a multiple of 4; the
            // updates fill the dispatch's arguments and the uniform block.
            unsafe {
                for (words, offset, size) in emptied {
                    d.cmd_fill_buffer(cmd, words.raw, offset, size, EMPTY_HALF);
                }
                // No workgroups, an empty queue: (x, y, z, length).
                d.cmd_update_buffer(cmd, buffers.large_args.raw, 0, bytemuck::cast_slice(&[0u32, 1, 1, 0]));
                d.cmd_update_buffer(cmd, buffers.uniforms.raw, 0, bytemuck::bytes_of(&uniforms));
            }
        };
        let uses = |queue: Access, args: Access| {
            let mut uses: Vec<_> = covered_words.iter().map(|&words| (words, Access::ComputeWrite)).collect();
            uses.extend([(&buffers.large, queue), (&buffers.large_args, args)]);
            uses.push((&buffers.uniforms, Access::UniformRead));
            uses
        };
        let triangles = covered.iter().map(|(_, member)| member.draw.mesh.index_count / 3).max().unwrap_or(0);
        let groups = triangles.div_ceil(COVERAGE_GROUP);
        let coverage_groups = [groups.min(MAX_GROUPS), groups.div_ceil(MAX_GROUPS)];
        let both = covered.iter().any(|(_, member)| member.shadow_area.is_some() && member.views.shadow.is_some());
        // Slices up to the last member covered; the others' triangle counts are 0.
        let slices = covered.last().map_or(0, |&(m, _)| m as u32 + 1);
        let one_tile =
            covered.iter().all(|(_, member)| fits_one_tile(member.draw.mesh.longest_edge, member.finest_pitch));
        let passes = |pipelines: &'s CoveragePipelines| -> Result<_> {
            let small = pipelines.small(one_tile)?;
            let small = if both { &small.both } else { &small.range };
            let cover =
                move |_: &GpuContext, cmd| buffers.set.dispatch_slices(cmd, small, &[], coverage_groups, slices);
            let large = move |_: &GpuContext, cmd| {
                buffers.set.dispatch_indirect(cmd, &pipelines.large, &[], &buffers.large_args)
            };
            Ok((cover, large))
        };
        let (cover, large) = passes(coverage)?;
        // The ties passes read the queue and its dispatch as the first passes left them.
        let reading_queue = || uses(Access::ComputeRead, Access::IndirectAndComputeRead);
        let mut steps = vec![
            Step::new(Vec::new(), cleared, prepare).timed("coverage: set-up"),
            Step::new(Vec::new(), uses(Access::ComputeWrite, Access::ComputeWrite), cover).timed("coverage"),
            Step::new(Vec::new(), reading_queue(), large).timed("coverage: large triangles"),
        ];
        if self.shared_words {
            // Both ties passes only raise the words' tagged triangles (their depths stay), so
            // they need no barrier between them.
            let (cover_ties, large_ties) = passes(pipelines.built(&pipelines.ties, Coverage::Ties)?)?;
            let ties = move |ctx: &GpuContext, cmd| {
                cover_ties(ctx, cmd);
                large_ties(ctx, cmd);
            };
            steps.push(Step::new(Vec::new(), reading_queue(), ties).timed("coverage: ties"));
        }
        Ok(steps)
    }
}

impl CoverageRun {
    /// The buffers and bindings of run number `run`, of `slots` (one a member), with a queue
    /// of `large_bytes`.
    fn new(
        ctx: &Arc<GpuContext>,
        layout: vk::DescriptorSetLayout,
        slots: &[&ComputeViews],
        large_bytes: u64,
        run: usize,
    ) -> Result<Self> {
        let large = Buffer::new(
            ctx,
            BufferDesc::gpu_storage(large_bytes.max(4)),
            &format!("coverage run {run} large triangles"),
        )?;
        let args = BufferDesc {
            usage: BufferDesc::gpu_storage(0).usage | vk::BufferUsageFlags::INDIRECT_BUFFER,
            ..BufferDesc::gpu_storage(16)
        };
        let large_args = Buffer::new(ctx, args, &format!("coverage run {run} large-triangle dispatch"))?;
        let uniform = BufferDesc {
            usage: vk::BufferUsageFlags::UNIFORM_BUFFER | vk::BufferUsageFlags::TRANSFER_DST,
            ..BufferDesc::gpu_storage(size_of::<CoverageUniforms>() as u64)
        };
        let uniforms = Buffer::new(ctx, uniform, &format!("coverage run {run} draws and members"))?;
        // Each member's words in each view; where a member or a view is missing, the run's
        // first range view's, never written.
        let member_words = |m: usize, shadow: bool| {
            let views = slots.get(m).unwrap_or(&slots[0]);
            match (shadow, &views.shadow) {
                (true, Some(words)) => &words.nearest,
                _ => &views.range.nearest,
            }
        };
        matches_shader_bindings!([RASTER_COMP, RASTER_LARGE_COMP, RASTER_TIES_COMP, RASTER_LARGE_TIES_COMP] {
            Coverage,
            range_words0,
            range_words1,
            range_words2,
            range_words3,
            shadow_words0,
            shadow_words1,
            shadow_words2,
            shadow_words3,
            Large,
            LargeArgs,
        });
        let mut buffers: Vec<&Buffer> = (0..COVERAGE_MEMBERS).map(|m| member_words(m, false)).collect();
        buffers.extend((0..COVERAGE_MEMBERS).map(|m| member_words(m, true)));
        buffers.extend([&large, &large_args]);
        let set = StorageSet::new(ctx, layout, &[], (&[&uniforms], &buffers), &format!("coverage run {run}"))?;
        Ok(Self { large, large_args, uniforms, set })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        /// A span of window x (or y) no longer than the longest edge `fits_one_tile` allows,
        /// in pixels, wherever it lies: the pixel centres of its box (first `floor(lo − ½)`,
        /// last `ceil(hi − ½)`, as shaders/raster/raster.comp's set_up finds them) number at most 8.
        /// (Spans up to 10 pixels are drawn: one of 6.5 may have 9.)
        #[test]
        fn a_span_fits_one_tile_allows_has_at_most_eight_pixel_centres(
            lo in -1000.0f64..1000.0,
            pixels in 0.0f64..10.0,
            pitch in 1e-4f64..10.0,
        ) {
            let edge = pixels * pitch;
            prop_assume!(fits_one_tile(edge, pitch));
            let hi = lo + edge / pitch;
            let (first, last) = ((lo - 0.5).floor(), (hi - 0.5).ceil());
            prop_assert!(last - first + 1.0 <= 8.0, "{lo}..{hi}: {first}..={last}");
        }
    }
}
