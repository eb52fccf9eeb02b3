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

mod coverage;
mod layout;
mod pipelines;
mod rig;
mod views;

pub(crate) use coverage::{CoverageGroup, CoverageMember};
pub(crate) use layout::{large_queue_bytes, VISIBILITY_WORD_BYTES};
pub use layout::{COVERAGE_MEMBERS, COVERAGE_STORAGE_BUFFERS, MAX_REACH_PIXELS};
pub(crate) use pipelines::{device_supports, ComputeRasterPipelines};
pub(crate) use rig::{RigCoverage, RigTarget, RigTargets, RigView};
pub(crate) use views::{ComputeTarget, ComputeViews};
