//! One rasterization pass of posed meshes into a view's attachments (targets.rs). The range
//! view and the shadow view differ only in their grid, their view rotation, their pipeline
//! and what the fragment shader writes.

use crate::error::Result;
use crate::gpu::shaders::matches_shader_struct;
use crate::gpu::{Buffer, GpuContext};
use crate::mesh::Solidity;
use crate::render::gpu_mesh::GpuMesh;
use crate::render::plan::Views;
use crate::render::targets::{ViewKind, ViewTargets};
use crate::sensor::{PixelRect, Scanner, ViewGrid};
use ash::vk;
use glam::{DMat4, DVec3};
use std::sync::Arc;

/// How a view projects: the scanner's views are orthographic; a rig's pinhole views project
/// (src/render/pinhole/). Both rasterizers draw either.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub enum Projection {
    Orthographic,
    Pinhole,
}

/// One draw as the shaders see it (`DrawData` in `shaders/raster/draw.glsl`, std430): the raster
/// shaders' push constants, and an entry of the shadow view's draw table, which the shadow
/// mask reads to reach the triangles the shadow view stored per pixel.
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
pub struct DrawConstants {
    view_from_model: [[f32; 4]; 3],
    grid: [f32; 4],
    size: [f32; 2],
    z_range: [f32; 2],
    triangles: [u32; 2],
    viewport_half_side: f32,
    viewport_inverse_half_side: f32,
    surface_ids: [u32; 2],
    viewport_centre: [f32; 2],
    label_base: u32,
    draw_index: u32,
    links: [u32; 2],
}

// Laid out as `DrawData` in every shader (build.rs checks that the std140 uniform block and
// the std430 push constants and buffers agree); 128 bytes, the push-constant size every
// Vulkan device supports.
matches_shader_struct!(
    DrawConstants,
    DrawData {
        view_from_model,
        grid,
        size,
        z_range,
        triangles,
        viewport_half_side,
        viewport_inverse_half_side,
        surface_ids,
        viewport_centre,
        label_base,
        draw_index,
        links,
    }
);
const _: () = assert!(size_of::<DrawConstants>() == 128);

/// The raster pipelines of one view. A view of one draw is drawn once with `nearest`. A view
/// of several draws is drawn twice, `depth_only` then `ties`, so that coincident faces of two
/// objects go to the lower label whatever the order of the draws (graphics.rs, `Depth`).
pub struct ViewPipelines {
    pub nearest: vk::Pipeline,
    pub depth_only: vk::Pipeline,
    pub ties: vk::Pipeline,
    pub order: DepthOrder,
}

/// Which way a view's depths run: an orthographic view's grow away from it (the nearest
/// surface has the least), a pinhole view's shrink (shaders/raster/draw.glsl,
/// `pinhole_clip_position`), which keeps f32 depths fine far from its centre.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum DepthOrder {
    NearestLeast,
    NearestGreatest,
}

impl ViewPipelines {
    /// No pipelines yet (null handles, which Vulkan's destroy ignores).
    pub const NULL: Self = Self {
        nearest: vk::Pipeline::null(),
        depth_only: vk::Pipeline::null(),
        ties: vk::Pipeline::null(),
        order: DepthOrder::NearestLeast,
    };

    /// Destroys the pipelines; no submission may still use them.
    pub fn destroy(&self, ctx: &GpuContext) {
        for pipeline in [self.nearest, self.depth_only, self.ties] {
            // SAFETY: owned handles (null ones are ignored), no longer in use.
            unsafe { ctx.device.destroy_pipeline(pipeline, None) };
        }
    }
}

impl DepthOrder {
    /// The depth nothing is drawn at: the depth buffer's clear value.
    pub fn empty(self) -> f32 {
        match self {
            DepthOrder::NearestLeast => 1.0,
            DepthOrder::NearestGreatest => 0.0,
        }
    }
}

/// One posed mesh in a view.
pub struct Draw<'a> {
    pub mesh: &'a GpuMesh,
    /// Model → range frame.
    pub pose: DMat4,
    pub label_base: u32,
}

impl DrawConstants {
    /// Composes, in f64, the move to the view's local origin (`origin`, range frame:
    /// `ViewGrid::local_origin`) ∘ view rotation ∘ pose ∘ the move from the mesh's origin
    /// (`Mesh::origin`, which its stored positions are offsets from), and rounds once to f32;
    /// the grid and
    /// depth range are offsets from that origin too. `draw_index` is the draw's entry in the
    /// draw table; `viewport_half_side` the device's (`GpuContext::viewport_half_side`).
    pub fn new(
        grid: &ViewGrid,
        view_from_range: DMat4,
        origin: DVec3,
        draw: &Draw,
        draw_index: u32,
        viewport_half_side: f32,
    ) -> Self {
        let local = view_from_range.transform_point3(origin);
        let view_from_model =
            DMat4::from_translation(-local) * view_from_range * draw.pose * DMat4::from_translation(draw.mesh.origin);
        let [x0, y0] = grid.origin;
        let viewport = ViewportFrame::new(grid, viewport_half_side);
        let view = ViewConstants {
            grid: [x0 - local.x, y0 - local.y, grid.pitch[0], grid.pitch[1]].map(|v| v as f32),
            size: [grid.width as f32, grid.height as f32],
            z_range: [grid.z_range.0 - local.z, grid.z_range.1 - local.z].map(|v| v as f32),
        };
        Self::in_view(view_from_model, view, (draw, draw_index), viewport)
    }

    /// Rounds `view_from_model` (composed in f64) to f32 and adds the view's and the draw's
    /// constants.
    fn in_view(
        view_from_model: DMat4,
        view: ViewConstants,
        (draw, draw_index): (&Draw, u32),
        viewport: ViewportFrame,
    ) -> Self {
        let row = |i| view_from_model.row(i).as_vec4().to_array();
        Self {
            view_from_model: [row(0), row(1), row(2)],
            grid: view.grid,
            size: view.size,
            z_range: view.z_range,
            triangles: draw.mesh.triangles.address_words(),
            viewport_half_side: viewport.half_side,
            viewport_inverse_half_side: 1.0 / viewport.half_side,
            surface_ids: draw.mesh.surface_ids.address_words(),
            viewport_centre: viewport.centre,
            label_base: draw.label_base,
            draw_index,
            links: draw.mesh.links.address_words(),
        }
    }
}

/// What a view gives a draw's constants besides its pose: `DrawData`'s grid, size and z range.
struct ViewConstants {
    grid: [f32; 4],
    size: [f32; 2],
    z_range: [f32; 2],
}

/// A pinhole view as the raster shaders draw it (shaders/raster/draw.glsl,
/// `pinhole_clip_position`): the move from the reference frame into its own, fx, fy, cx, cy
/// with cy counted from the top of the attachments (its band's first row added), its size,
/// and its depth constants s and s / far.
#[derive(Debug, Clone, Copy)]
pub struct PinholeDrawing {
    pub view_from_reference: DMat4,
    pub intrinsics: [f64; 4],
    pub size: (u32, u32),
    pub depth: [f64; 2],
}

impl PinholeDrawing {
    /// The depth of its near plane, which the clipper cuts at: s / (1 + s / far).
    pub fn near_plane(&self) -> f64 {
        let [s, s_over_far] = self.depth;
        s / (1.0 + s_over_far)
    }
}

impl DrawConstants {
    /// A draw's constants in a pinhole view, `viewport` the band's (rounded once to f32 from
    /// a transform composed in f64, as [`DrawConstants::new`] does). `None` where a value
    /// does not hold in f32 (a pose or a depth constant beyond its range).
    pub fn pinhole(view: &PinholeDrawing, draw: &Draw, draw_index: u32, viewport: ViewportFrame) -> Option<Self> {
        let view_from_model = view.view_from_reference * draw.pose * DMat4::from_translation(draw.mesh.origin);
        let constants = ViewConstants {
            grid: view.intrinsics.map(|v| v as f32),
            size: [view.size.0 as f32, view.size.1 as f32],
            z_range: view.depth.map(|v| v as f32),
        };
        Self::in_view(view_from_model, constants, (draw, draw_index), viewport).held_in_f32()
    }

    /// The constants, where every value held in f32 (a pose, a grid or a depth constant did
    /// not overflow).
    pub fn held_in_f32(self) -> Option<Self> {
        let mut floats = self.view_from_model.iter().flatten().chain(&self.grid).chain(&self.z_range);
        floats.all(|v| v.is_finite()).then_some(self)
    }
}

/// One view to render: its pipelines, attachments, grid, the rotation from the range frame
/// into it (identity for the range view, R_y(−θ) for the shadow view), and the pixels to
/// clear and draw (the whole grid, or a batch hypothesis' footprint; the rest of the
/// attachments is left as it was and must not be read).
pub struct ViewPass<'a> {
    pub pipelines: &'a ViewPipelines,
    pub layout: vk::PipelineLayout,
    pub targets: &'a ViewTargets,
    pub grid: &'a ViewGrid,
    pub view_from_range: DMat4,
    /// The local origin, range frame (`Views::origin`).
    pub origin: DVec3,
    pub area: PixelRect,
}

/// Records a view pass: clears (colour 0, depth 1) then draws every mesh, numbering the draws
/// from `first_draw_index`. The caller has moved the attachments to their attachment layouts.
pub fn record_view(ctx: &GpuContext, cmd: vk::CommandBuffer, pass: &ViewPass, draws: &[Draw], first_draw_index: u32) {
    let half_side = ctx.viewport_half_side();
    let constants: Vec<_> = (first_draw_index..)
        .zip(draws)
        .map(|(index, draw)| {
            let constants = DrawConstants::new(pass.grid, pass.view_from_range, pass.origin, draw, index, half_side);
            (constants, cull_mode(draw.mesh.solidity))
        })
        .collect();
    let band = Band { area: pass.area, viewport: ViewportFrame::new(pass.grid, half_side), draws: &constants };
    record_bands(ctx, cmd, (pass.pipelines, pass.layout), pass.targets, pass.area, &[band], draws);
}

/// One view drawn into a band of a pass's attachments (several views can share them: a
/// rig's witnesses, src/render/pinhole/): the pixels it draws, the viewport it is drawn
/// through, and each draw's constants and cull mode in it, in the order of the draws.
pub struct Band<'a> {
    pub area: PixelRect,
    pub viewport: ViewportFrame,
    pub draws: &'a [(DrawConstants, vk::CullModeFlags)],
}

/// Records one rendering into `targets` over `area`: clears it (colour 0, depth to the
/// pipelines' empty depth) then draws every mesh into each band. The caller has moved the
/// attachments to their attachment layouts.
pub fn record_bands(
    ctx: &GpuContext,
    cmd: vk::CommandBuffer,
    (pipelines, layout): (&ViewPipelines, vk::PipelineLayout),
    targets: &ViewTargets,
    area: PixelRect,
    bands: &[Band],
    draws: &[Draw],
) {
    let d = &ctx.device;
    let rect = |a: PixelRect| vk::Rect2D {
        offset: vk::Offset2D { x: a.col as i32, y: a.row as i32 },
        extent: vk::Extent2D { width: a.width, height: a.height },
    };
    // All-zero bits: 0 as an integer and 0.0 as a float.
    let zero = vk::ClearValue { color: vk::ClearColorValue { uint32: [0; 4] } };
    let attachments: Vec<_> = targets
        .colour
        .iter()
        .map(|image| {
            vk::RenderingAttachmentInfo::default()
                .image_view(image.view)
                .image_layout(vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL)
                .load_op(vk::AttachmentLoadOp::CLEAR)
                .store_op(vk::AttachmentStoreOp::STORE)
                .clear_value(zero)
        })
        .collect();
    let empty = vk::ClearDepthStencilValue { depth: pipelines.order.empty(), stencil: 0 };
    let depth = vk::RenderingAttachmentInfo::default()
        .image_view(targets.depth.view)
        .image_layout(vk::ImageLayout::DEPTH_ATTACHMENT_OPTIMAL)
        .load_op(vk::AttachmentLoadOp::CLEAR)
        .store_op(vk::AttachmentStoreOp::DONT_CARE)
        .clear_value(vk::ClearValue { depth_stencil: empty });
    // The attachments may be larger than the grid (batch slots fit their largest view): the
    // render area is within the grid.
    let info = vk::RenderingInfo::default()
        .render_area(rect(area))
        .layer_count(1)
        .color_attachments(&attachments)
        .depth_attachment(&depth);
    // SAFETY: cmd is recording; targets, pipeline and meshes outlive the submission.
    unsafe {
        ctx.cmd_begin_rendering(cmd, &info);
        for band in bands {
            d.cmd_set_viewport(cmd, 0, &[band.viewport.viewport()]);
            d.cmd_set_scissor(cmd, 0, &[rect(band.area)]);
            let mut numbered: Vec<(usize, &Draw)> = draws.iter().enumerate().collect();
            let colour_pipeline = match numbered.len() {
                1 => pipelines.nearest,
                _ => {
                    d.cmd_bind_pipeline(cmd, vk::PipelineBindPoint::GRAPHICS, pipelines.depth_only);
                    record_draws(ctx, cmd, layout, band, &numbered);
                    // Among ties the last drawn stays: draw the lowest label last.
                    numbered.sort_by_key(|(_, draw)| std::cmp::Reverse(draw.label_base));
                    pipelines.ties
                }
            };
            d.cmd_bind_pipeline(cmd, vk::PipelineBindPoint::GRAPHICS, colour_pipeline);
            record_draws(ctx, cmd, layout, band, &numbered);
        }
        ctx.cmd_end_rendering(cmd);
    }
}

/// The viewport a view is drawn through: a square of 2 × `half_side` pixels (a power of two)
/// centred on the view's centre rounded down to a whole pixel (a device may hold a viewport's
/// corner to whole pixels: viewportSubPixelBits), far larger than the view; the render area
/// keeps the fragments to the view. The raster shaders and the compute rasterizer read its
/// centre and half side from the draw's constants (shaders/raster/draw.glsl, `clip_position`).
///
/// Why so large: the graphics pipeline clips a triangle that crosses the viewport's edge
/// (lavapipe has no guard band where a depth attachment is bound), and the corners the
/// clipper makes are snapped anew, so the kept part's edges move by up to a snapping step and
/// pixel centres that close to them are covered otherwise than the whole triangle covers
/// them, as the compute rasterizer, which never clips, covers them. Only a triangle reaching
/// `half_side` pixels from the view's centre is clipped now. raster.vert multiplies by the
/// inverse of `half_side` and the viewport transform by `half_side`, both exactly (powers of
/// two), so the window coordinates are the same bits whether a device fuses the transform's
/// multiply-add or not.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ViewportFrame {
    /// In window coordinates, whole pixels.
    pub centre: [f32; 2],
    pub half_side: f32,
}

impl ViewportFrame {
    /// The frame of a view's viewport, `half_side` the device's
    /// (`GpuContext::viewport_half_side`), at least half the view's larger side
    /// (`GpuContext::max_view_side`).
    pub fn new(grid: &ViewGrid, half_side: f32) -> Self {
        Self::around(grid.full(), half_side)
    }

    /// The frame of a viewport around `area` of the attachments, its centre rounded down to a
    /// whole pixel, with `half_side` as in [`ViewportFrame::new`].
    pub fn around(area: PixelRect, half_side: f32) -> Self {
        Self { centre: [(area.col + area.width / 2) as f32, (area.row + area.height / 2) as f32], half_side }
    }

    fn viewport(&self) -> vk::Viewport {
        vk::Viewport {
            x: self.centre[0] - self.half_side,
            y: self.centre[1] - self.half_side,
            width: 2.0 * self.half_side,
            height: 2.0 * self.half_side,
            min_depth: 0.0,
            max_depth: 1.0,
        }
    }
}

/// Which of a mesh's triangles the graphics pipeline culls: a solid's facing away from the
/// camera, which are never the first hit (src/mesh/solid.rs), and none of an open mesh's. The
/// compute rasterizer skips the same ones (raster/compute/). (A pinhole view may lie inside a
/// solid, and then culls none: src/render/pinhole/.)
pub(crate) fn cull_mode(solidity: Solidity) -> vk::CullModeFlags {
    match solidity {
        Solidity::Outward => vk::CullModeFlags::BACK,
        Solidity::Inward => vk::CullModeFlags::FRONT,
        Solidity::Open => vk::CullModeFlags::NONE,
    }
}

/// Records the draws, each with its constants and cull mode in `band` (by its place among
/// the band's draws), into the bound pipeline.
fn record_draws(
    ctx: &GpuContext,
    cmd: vk::CommandBuffer,
    layout: vk::PipelineLayout,
    band: &Band,
    draws: &[(usize, &Draw)],
) {
    let d = &ctx.device;
    for &(place, draw) in draws {
        let (constants, cull) = band.draws[place];
        // SAFETY: cmd is recording inside a rendering scope with a pipeline of `layout`
        // bound, its cull mode dynamic; the meshes outlive the submission.
        unsafe {
            ctx.cmd_set_cull_mode(cmd, cull);
            d.cmd_push_constants(
                cmd,
                layout,
                vk::ShaderStageFlags::VERTEX | vk::ShaderStageFlags::FRAGMENT,
                0,
                bytemuck::bytes_of(&constants),
            );
            d.cmd_bind_vertex_buffers(cmd, 0, &[draw.mesh.vertices.raw], &[0]);
            d.cmd_bind_index_buffer(cmd, draw.mesh.indices.raw, 0, vk::IndexType::UINT32);
            d.cmd_draw_indexed(cmd, draw.mesh.index_count, 1, 0, 0, 0);
        }
    }
}

/// A view's draw table: for each group of draws seen on planned views, in order, each draw's
/// constants in that view, numbered consecutively from 0 (a job's `first_draw_index` is the
/// number of draws before it). The shadow mask reads the shadow view's to reach the triangles
/// the shadow view stored (shaders/stages/shadow_mask.comp); the compute rasterizer's passes read
/// both, its coverage passes from a uniform block the host writes with their entries (one
/// command a coverage dispatch, not a copy a view: raster/compute/), so the entries are kept
/// on the host too.
pub(crate) struct DrawTable {
    pub buffer: Buffer,
    pub entries: Vec<DrawConstants>,
}

/// A view's [`DrawTable`]; `None` for the shadow view where there is none (mode `none` or
/// θ = 0, which every job of a submission shares).
pub(crate) fn draw_table<'a>(
    ctx: &Arc<GpuContext>,
    kind: ViewKind,
    sensor: &Scanner,
    groups: impl IntoIterator<Item = (&'a Views, &'a [Draw<'a>])>,
) -> Result<Option<DrawTable>> {
    let view_from_range = match kind {
        ViewKind::Range => DMat4::IDENTITY,
        ViewKind::Shadow => sensor.to_shadow_frame(),
    };
    let half_side = ctx.viewport_half_side();
    let mut entries = Vec::new();
    for (views, draws) in groups {
        let grid = match kind {
            ViewKind::Range => &views.range,
            ViewKind::Shadow => match &views.shadow {
                Some(grid) => grid,
                None => return Ok(None),
            },
        };
        for draw in draws {
            let index = entries.len() as u32;
            entries.push(DrawConstants::new(grid, view_from_range, views.origin, draw, index, half_side));
        }
    }
    let name = format!("{kind:?} view draw table");
    match entries.is_empty() {
        true => Ok(None),
        false => {
            let buffer = Buffer::with_data(ctx, vk::BufferUsageFlags::STORAGE_BUFFER, &entries, &name)?;
            Ok(Some(DrawTable { buffer, entries }))
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The viewport holds every pixel of a view of any size up to twice its half side, at
    /// whole-pixel corners, and its transform maps the view's pixels onto the framebuffer's:
    /// window x = ndc × half side + centre, as Vulkan's viewport transform (x + width / 2 as
    /// the offset) computes it.
    #[test]
    fn a_views_viewport_holds_its_pixels_at_whole_pixel_corners() {
        let half_side = 8192.0;
        for side in [1, 2, 95, 96, 4097, 16383, 16384] {
            let grid = ViewGrid {
                origin: [0.0; 2],
                pitch: [1.0; 2],
                width: side,
                height: side - side / 2,
                z_range: (0.0, 1.0),
            };
            let viewport = ViewportFrame::new(&grid, half_side).viewport();
            let (right, bottom) = (viewport.x + viewport.width, viewport.y + viewport.height);
            assert!(viewport.x <= 0.0 && right >= side as f32, "{side}: columns {} to {right}", viewport.x);
            assert!(viewport.y <= 0.0 && bottom >= grid.height as f32, "{side}: rows {} to {bottom}", viewport.y);
            assert_eq!((viewport.x.fract(), viewport.y.fract()), (0.0, 0.0), "{side}: whole-pixel corner");
            assert_eq!((viewport.width, viewport.height), (16384.0, 16384.0));
            let offset = viewport.x + viewport.width / 2.0;
            assert_eq!(offset, ViewportFrame::new(&grid, half_side).centre[0], "{side}: the offset is the centre");
        }
    }
}
