//! The constants the shaders and the Rust code share, each defined once, here. `build.rs`
//! includes this file and writes each constant as a macro of a header it generates,
//! `contract.glsl`, which the shaders include (`#include "contract.glsl"`); the Rust code
//! uses them from here. So neither side can change one alone. (What a pipeline varies, such
//! as the counts layout and the edge links' packing, reaches the shaders as specialization
//! constants instead, given where the pipeline is built.)
//!
//! Each constant here is named in build.rs's `contract_glsl`, which only an edit of both
//! keeps true; a shader using one that build.rs does not write fails to build.

/// Heights (depths) this close, relative to the scene's (the view's) largest coordinate, are a
/// tie: 2^-17, about 64 f32 ulps, the rounding of poses (README "the tie rule"). Exact mode
/// (src/exact/) uses it as it is; the GPU paths add an allowance for depths worked out from
/// snapped corners (`tie_depth`, shaders/raster/draw.glsl), which exact mode has none of.
pub const TIE_RELATIVE: f64 = 1.0 / 131072.0;

/// An edge link that names no triangle (src/mesh/adjacency.rs).
pub const NO_NEIGHBOUR: u32 = u32::MAX;

/// Each half of a pixel's visibility word where no triangle covers it: the compute rasterizer
/// fills the words with it before its coverage passes (shaders/raster/visibility_word.glsl).
pub const EMPTY_HALF: u32 = u32::MAX;

/// Where a member's place starts above a triangle's index, in the compute rasterizer's words
/// of a view of several draws and in its queue of large triangles (shaders/raster/raster_compute.glsl):
/// meshes have fewer than 2^29 triangles (`mesh::MAX_LINKED_TRIANGLES`).
pub const MEMBER_SHIFT: u32 = 29;

/// Most jobs one coverage dispatch of the compute rasterizer covers (shaders/raster/raster.comp binds
/// each member's words, four bindings a view, which it checks, and src/render/raster/compute/
/// groups its slots by it).
pub const COVERAGE_MEMBERS: usize = 4;

/// The bit of a queued large triangle's entry that says its view (0 range, 1 shadow), above
/// its member's place (shaders/raster/raster.comp).
pub const QUEUE_VIEW_BIT: u32 = 31;

/// Invocations a workgroup of the compute rasterizer's coverage passes (`local_size_x` in
/// shaders/raster/raster.comp): each covers a triangle, or in the large triangles' pass a row.
pub const COVERAGE_GROUP: u32 = 64;

/// A view's kind as the shaders' view functions take it (shaders/common/view.glsl;
/// [`View`](crate::sensor::View)): an orthographic grid.
pub const VIEW_ORTHOGRAPHIC: u32 = 0;

/// A view's kind as the shaders' view functions take it: a pinhole camera's intrinsics.
pub const VIEW_PINHOLE: u32 = 1;
