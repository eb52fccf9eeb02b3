//! Pipelines a renderer builds only when a call first needs them (the effects', the compute
//! rasterizer's), kept for every later call, and written to the device's pipeline cache on
//! disk as soon as they are built (src/gpu/pipeline_cache.rs), so that a run killed later
//! still leaves them for the next.

use crate::error::Result;
use crate::gpu::GpuContext;
use std::sync::OnceLock;

/// What `cell` holds, built by `build` on first use on `ctx`. Two threads may both build it;
/// the one that comes second drops its own (std's fallible `get_or_try_init` is not stable).
pub(super) fn built_once<'a, T>(
    ctx: &GpuContext,
    cell: &'a OnceLock<T>,
    build: impl FnOnce() -> Result<T>,
) -> Result<&'a T> {
    if let Some(built) = cell.get() {
        return Ok(built);
    }
    let built = build()?;
    ctx.save_pipeline_cache();
    Ok(cell.get_or_init(|| built))
}
