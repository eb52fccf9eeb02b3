//! Pipelines a renderer builds only when a call first needs them (the effects', the compute
//! rasterizer's), kept for every later call.

use crate::error::Result;
use std::sync::OnceLock;

/// What `cell` holds, built by `build` on first use. Two threads may both build it; the one
/// that comes second drops its own (std's fallible `get_or_try_init` is not stable).
pub(super) fn built_once<T>(cell: &OnceLock<T>, build: impl FnOnce() -> Result<T>) -> Result<&T> {
    if let Some(built) = cell.get() {
        return Ok(built);
    }
    let built = build()?;
    Ok(cell.get_or_init(|| built))
}
