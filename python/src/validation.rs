//! Vulkan validation's messages, for the package's test suite: Python has no test harness of the
//! crate's to read them, so the package keeps the log of every device context it opens with
//! validation on (RANGESYNTH_VALIDATION=1) and hands what they reported to
//! `rangesynth.validation_messages()`. A context's log outlives it (`ValidationLog`), so what
//! the layer reports while a renderer is torn down (objects left alive) is read too.

use pyo3::prelude::*;
use rangesynth::gpu::ValidationLog;
use rangesynth::Renderer;
use std::sync::{Mutex, MutexGuard, OnceLock};

fn logs() -> MutexGuard<'static, Vec<ValidationLog>> {
    static LOGS: OnceLock<Mutex<Vec<ValidationLog>>> = OnceLock::new();
    LOGS.get_or_init(Default::default).lock().unwrap_or_else(|p| p.into_inner())
}

/// `renderer`, its context's validation log kept where validation is on.
pub fn watched(renderer: Renderer) -> Renderer {
    if let Some(log) = renderer.context().validation_log() {
        logs().push(log);
    }
    renderer
}

/// The messages Vulkan validation reported since the last call, on every device context this
/// process opened with validation on (RANGESYNTH_VALIDATION=1), those since closed included.
#[pyfunction]
pub fn validation_messages() -> Vec<String> {
    let mut logs = logs();
    let messages = logs.iter().flat_map(ValidationLog::take).collect();
    // A closed context's log, read, holds nothing more.
    logs.retain(|log| !log.is_closed());
    messages
}
