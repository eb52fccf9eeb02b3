//! The compute rasterizer's pipelines: coverage, specialized by how many jobs a dispatch
//! covers and which views, with and without the tiles' code; the ties passes; the resolve
//! passes; a rig's pinhole views' variants of them (rig.rs); and whether a device can run them
//! at all.

use super::layout::{RasterView, COVERAGE_MEMBERS, COVERAGE_STORAGE_BUFFERS, DEAL_BLOCK, DEAL_STRIPES, MAX_GROUPS};
use crate::error::Result;
use crate::gpu::{shaders, ComputePipeline, GpuContext, SetShape};
use crate::render::built_once::built_once;
use crate::render::raster::draw::Projection;
use crate::render::stages::mask_pipelines::MaskPipelines;
use crate::render::stages::shadow_mask::{mask_pipelines, MaskVariant};
use crate::render::targets::ViewKind;
use std::sync::{Arc, OnceLock};

/// What the coverage pass binds: the uniform block (the members' draws and constants), each
/// member's words in each view, the large-triangle queue and its dispatch arguments.
const COVERAGE_SET: SetShape = SetShape { images: 0, uniform_buffers: 1, storage_buffers: COVERAGE_STORAGE_BUFFERS };

/// Whether `ctx`'s device can run the compute rasterizer: 64-bit integers and buffer atomics,
/// and the bindings of its coverage pass within the device's limits (the check its pipelines'
/// creation makes, which would refuse them).
pub fn device_supports(ctx: &GpuContext) -> bool {
    ctx.has_int64_atomics() && COVERAGE_SET.check_fits(0, &ctx.limits, "coverage").is_ok()
}

/// The coverage passes' pipelines for dispatches of `members` jobs, or (`Ties`) the passes
/// after them that decide the ties between draws sharing words.
pub(super) struct CoveragePipelines {
    /// The small triangles' coverage, covering boxes over a tile by tiles; and without the
    /// tiles' code, for meshes whose every triangle fits one tile (`fits_one_tile`), built on
    /// first use.
    pub(super) tiled: SmallTriangles,
    pub(super) one_tile: OnceLock<SmallTriangles>,
    /// The large triangles' coverage: of the queue's start (a pinhole view's triangles the
    /// clipper keeps whole), and of a pinhole view's triangles the clipper may cut, queued
    /// from its end.
    pub(super) large: ComputePipeline,
    pub(super) clipped: Option<ComputePipeline>,
    pub(super) ctx: Arc<GpuContext>,
    pub(super) members: u32,
    pub(super) kind: Coverage,
    pub(super) projection: Projection,
}

/// The small triangles' coverage of the range view alone, and of both views (a rig's: its
/// reference view and a witness's band).
pub(super) struct SmallTriangles {
    pub(super) range: ComputePipeline,
    pub(super) both: ComputePipeline,
}

/// Whether every triangle of a mesh whose longest edge is `longest_edge` (model units) has a
/// box of at most 8 pixels a side (one tile) in views of pixels `pitch` or larger: its
/// projection spans at most that edge, and a span of `w` pixels from `lo` has its box's pixel
/// centres from floor(`lo` − ½) to ceil(`lo` + `w` − ½), at most ceil(`w`) + 2 of them, so 5.9
/// pixels (below 6, for the rounding of poses and corners) leaves at most 8. The small
/// triangles' pass then leaves out the tiles' code, which a software rasterizer runs whatever
/// the boxes, so dense meshes cover faster there.
pub(super) fn fits_one_tile(longest_edge: f64, pitch: f64) -> bool {
    longest_edge <= 5.9 * pitch
}

/// Which of shaders/raster/raster.comp's two kinds of coverage passes.
#[derive(Clone, Copy, PartialEq, Eq)]
pub(super) enum Coverage {
    /// The nearest triangle a pixel.
    Nearest,
    /// Among the triangles within the tie depth of the nearest, the last drawn (TIES).
    Ties,
}

impl CoveragePipelines {
    pub(super) fn new(ctx: &Arc<GpuContext>, members: u32, kind: Coverage, projection: Projection) -> Result<Self> {
        use Projection::{Orthographic, Pinhole};
        let large = match (kind, projection) {
            (Coverage::Nearest, Orthographic) => shaders::RASTER_LARGE_COMP,
            (Coverage::Ties, Orthographic) => shaders::RASTER_LARGE_TIES_COMP,
            (Coverage::Nearest, Pinhole) => shaders::RASTER_PINHOLE_LARGE_COMP,
            (Coverage::Ties, Pinhole) => shaders::RASTER_PINHOLE_LARGE_TIES_COMP,
        };
        let name = format!("compute raster coverage ({}large triangles)", projection_name(projection));
        let clipped = match (kind, projection) {
            (_, Orthographic) => None,
            (Coverage::Nearest, Pinhole) => Some(shaders::RASTER_PINHOLE_LARGE_CLIPPED_COMP),
            (Coverage::Ties, Pinhole) => Some(shaders::RASTER_PINHOLE_LARGE_TIES_CLIPPED_COMP),
        };
        let clipped_name = "compute raster coverage (pinhole view, large triangles the clipper may cut)";
        let clipped = clipped.map(|code| covering(ctx, (members, kind), code, (2, true), clipped_name)).transpose()?;
        Ok(Self {
            tiled: SmallTriangles::new(ctx, (members, kind, projection), true)?,
            one_tile: OnceLock::new(),
            large: covering(ctx, (members, kind), large, (2, true), &name)?,
            clipped,
            ctx: ctx.clone(),
            members,
            kind,
            projection,
        })
    }

    /// The small triangles' pipelines, with the tiles' code or (`one_tile`) without.
    pub(super) fn small(&self, one_tile: bool) -> Result<&SmallTriangles> {
        if !one_tile {
            return Ok(&self.tiled);
        }
        let shape = (self.members, self.kind, self.projection);
        built_once(&self.ctx, &self.one_tile, || SmallTriangles::new(&self.ctx, shape, false))
    }
}

/// How a pipeline's name tells a pinhole variant.
fn projection_name(projection: Projection) -> &'static str {
    match projection {
        Projection::Orthographic => "",
        Projection::Pinhole => "pinhole view, ",
    }
}

impl SmallTriangles {
    pub(super) fn new(
        ctx: &Arc<GpuContext>,
        (members, kind, projection): (u32, Coverage, Projection),
        tiles: bool,
    ) -> Result<Self> {
        use Projection::{Orthographic, Pinhole};
        let code = match (kind, projection) {
            (Coverage::Nearest, Orthographic) => shaders::RASTER_COMP,
            (Coverage::Ties, Orthographic) => shaders::RASTER_TIES_COMP,
            (Coverage::Nearest, Pinhole) => shaders::RASTER_PINHOLE_COMP,
            (Coverage::Ties, Pinhole) => shaders::RASTER_PINHOLE_TIES_COMP,
        };
        let name = |view: &str| {
            let tiles = if tiles { "" } else { ", one tile" };
            format!("compute raster coverage ({}{view}{tiles})", projection_name(projection))
        };
        Ok(Self {
            range: covering(ctx, (members, kind), code, (1, tiles), &name("range view"))?,
            both: covering(ctx, (members, kind), code, (2, tiles), &name("both views"))?,
        })
    }

    /// The pipeline covering the range view, and where `both`, the shadow view too.
    pub(super) fn covering(&self, both: bool) -> &ComputePipeline {
        if both {
            &self.both
        } else {
            &self.range
        }
    }
}

/// A coverage pipeline of shaders/raster/raster.comp's variant `code`, for dispatches of `members`
/// jobs of `kind`, covering `views` (the range view, or both; the large triangles' pass reads
/// each queued triangle's view), boxes over a tile by tiles or not.
pub(super) fn covering(
    ctx: &Arc<GpuContext>,
    (members, kind): (u32, Coverage),
    code: &[u8],
    (views, tiles): (u32, bool),
    name: &str,
) -> Result<ComputePipeline> {
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
    ComputePipeline::new(ctx, COVERAGE_SET, 0, code, &constants, &format!("{name}, {dispatch}"))
}

pub struct ComputeRasterPipelines {
    pub(super) ctx: Arc<GpuContext>,
    /// Coverage a job a dispatch; coverage of several, and the ties passes of a view of
    /// several draws, built on first use.
    pub(super) single: CoveragePipelines,
    pub(super) grouped: OnceLock<CoveragePipelines>,
    pub(super) ties: OnceLock<CoveragePipelines>,
    /// A rig's pinhole views' coverage and ties passes (its draws the members), its views'
    /// coverage of a job of one draw, and the reference view's resolve, built on first use
    /// (rig.rs).
    pub(super) pinhole: OnceLock<CoveragePipelines>,
    pub(super) pinhole_one_draw: OnceLock<CoveragePipelines>,
    pub(super) pinhole_ties: OnceLock<CoveragePipelines>,
    pub(super) resolve_pinhole: OnceLock<ComputePipeline>,
    /// The range view's resolve where its words hold one draw, and where they hold several;
    /// the shadow view's where they hold several.
    pub(super) resolve: ComputePipeline,
    pub(super) resolve_several: ComputePipeline,
    pub(super) resolve_shadow: ComputePipeline,
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
            single: CoveragePipelines::new(ctx, 1, Coverage::Nearest, Projection::Orthographic)?,
            grouped: OnceLock::new(),
            ties: OnceLock::new(),
            pinhole: OnceLock::new(),
            pinhole_one_draw: OnceLock::new(),
            pinhole_ties: OnceLock::new(),
            resolve_pinhole: OnceLock::new(),
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
            mask: mask_pipelines(ctx, MaskVariant::Words)?,
            mask_for_scoring: mask_pipelines(ctx, MaskVariant::WordsForScoring)?,
        })
    }

    /// The coverage pipelines for dispatches of `members` jobs (1 to [`COVERAGE_MEMBERS`]): one
    /// job's, or the grouped ones, which cover up to [`COVERAGE_MEMBERS`].
    pub(super) fn coverage(&self, members: usize) -> Result<&CoveragePipelines> {
        if members == 1 {
            return Ok(&self.single);
        }
        self.built(&self.grouped, Coverage::Nearest)
    }

    /// The grouped pipelines of `kind`, in `cell`, built on first use.
    pub(super) fn built<'s>(
        &self,
        cell: &'s OnceLock<CoveragePipelines>,
        kind: Coverage,
    ) -> Result<&'s CoveragePipelines> {
        self.built_for(cell, (kind, Projection::Orthographic))
    }

    /// The grouped pipelines of `kind` for views of `projection`, in `cell`, built on first
    /// use.
    pub(super) fn built_for<'s>(
        &self,
        cell: &'s OnceLock<CoveragePipelines>,
        (kind, projection): (Coverage, Projection),
    ) -> Result<&'s CoveragePipelines> {
        built_once(&self.ctx, cell, || CoveragePipelines::new(&self.ctx, COVERAGE_MEMBERS as u32, kind, projection))
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
