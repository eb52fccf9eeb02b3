//! What the compute rasterizer's passes share with shaders/raster/raster.comp and
//! raster_compute.glsl: the structs they read (checked against the shaders at compile time),
//! the sizes of their buffers and the limits on what they can cover.

use crate::gpu::shaders::matches_shader_struct;
use crate::mesh::Solidity;
use crate::render::raster::draw::DrawConstants;
use crate::shader_contract::{MEMBER_SHIFT, QUEUE_VIEW_BIT};

/// One view as both passes see it; matches `RasterView` in shaders/raster/raster_compute.glsl.
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
pub(super) struct RasterView {
    pub(super) area: [u32; 4],
    pub(super) draw: u32,
    pub(super) stride: u32,
    pub(super) _pad: [u32; 2],
}

/// One member's constants in the coverage passes' uniform block; matches `Member` in
/// shaders/raster/raster.comp (std140: the same offsets, as it holds no vec3 and no array of scalars).
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
pub(super) struct MemberConstants {
    pub(super) views: [RasterView; 2],
    pub(super) triangles: u32,
    pub(super) cull: i32,
    pub(super) dealt_rows: u32,
    /// Where the members share words (a view of several draws), the member's place in the
    /// ties order; else 0.
    pub(super) place: u32,
    /// 1 where the member's range view is its own, of one draw: its words then hold z keys
    /// (shaders/raster/visibility_word.glsl), from which its resolve reads z; 0 where members share
    /// words, whose ties passes compare depths.
    pub(super) z_keys: u32,
    /// A rig's dispatch of two pinhole views: the second's cull (raster/compute/rig.rs); else
    /// `cull`.
    pub(super) second_cull: i32,
    pub(super) _pad: [u32; 2],
}

matches_shader_struct!(RasterView, RasterView { area, draw, stride });
matches_shader_struct!(MemberConstants, Member { views, triangles, cull, dealt_rows, place, z_keys, second_cull });

/// The coverage passes' uniform block; matches `Coverage` in shaders/raster/raster.comp (std140: the
/// same offsets, as DrawData and Member keep them and their sizes are multiples of 16). Each
/// member's draw in each view: draws[m] its range view's, draws[COVERAGE_MEMBERS + m] its
/// shadow view's; then each member's constants.
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
pub(super) struct CoverageUniforms {
    pub(super) draws: [DrawConstants; 2 * COVERAGE_MEMBERS],
    pub(super) members: [MemberConstants; COVERAGE_MEMBERS],
}

matches_shader_struct!(CoverageUniforms, Coverage { draws, members });

/// `cull` of the coverage pass: which triangles it skips, by the sign of their view-frame
/// normal's z (the camera looks along −z). Only a solid's are skipped (src/mesh/solid.rs).
pub(super) fn cull_sign(solidity: Solidity) -> i32 {
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

/// The large triangles' queue's indirect dispatches (`LargeArgs`, shaders/raster/raster.comp),
/// each (x, y, z, length): the queue's start's part, and its end's, a pinhole view's
/// triangles the clipper may cut, which passes of their own cover so that the others hold no
/// clipping code (a software rasterizer runs a shader's every instruction whatever its
/// branches).
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
pub(super) struct LargeArgs {
    queue_parts: [[u32; 4]; 2],
}

matches_shader_struct!(LargeArgs, LargeArgs { queue_parts });

impl LargeArgs {
    /// An empty queue: no workgroups in either dispatch.
    pub const EMPTY: Self = Self { queue_parts: [[0, 1, 1, 0]; 2] };
    /// Where each dispatch's arguments lie in the buffer: the start's part, the end's.
    pub const START: u64 = std::mem::offset_of!(Self, queue_parts) as u64;
    pub const END: u64 = Self::START + size_of::<[u32; 4]>() as u64;
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
pub(super) const DEAL_BLOCK: u32 = 2;
pub(super) const DEAL_STRIPES: u32 = 16;

/// Most workgroups along one dispatch dimension that every device allows: the coverage pass's
/// rows of workgroups, and the most the large triangles' indirect dispatch is given (the
/// shader's MAX_GROUPS, a specialization constant).
pub(super) const MAX_GROUPS: u32 = 65_535;

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
