//! Render targets kept between calls: a view's attachments cost an allocation and several
//! Vulkan objects each, which a `verify` of one hypothesis, or a daemon rendering image after
//! image, would otherwise pay on every call. Targets are keyed by view kind and size; the pool
//! keeps those of the latest calls, at most [`KEPT`], so the memory it holds stays bounded
//! by what recent calls used.

use crate::error::Result;
use crate::gpu::GpuContext;
use crate::render::targets::{ViewKind, ViewTargets};
use std::sync::{Arc, Mutex};

/// Most slots one batch may keep (src/verify/batch.rs, `default_slots`).
pub const MAX_SLOTS: usize = 64;

/// Most chunks a verification keeps in flight at once (src/verify/lanes.rs): each holds its
/// batch's slots.
pub const MAX_CHUNKS_IN_FLIGHT: usize = 4;

/// Views' targets the pool keeps when no call uses them: those of a verification's most chunks
/// in flight (src/verify/lanes.rs), each of the most slots a batch may keep, each slot with a
/// range and a shadow view (a call returns only those it used).
pub const KEPT: usize = MAX_CHUNKS_IN_FLIGHT * 2 * MAX_SLOTS;

/// Free targets with their kind and size.
type Kept = (ViewKind, (u32, u32), ViewTargets);

#[derive(Default)]
pub(crate) struct TargetPool {
    /// Free targets, the most recently returned last.
    free: Mutex<Vec<Kept>>,
}

impl TargetPool {
    /// Targets of this kind and size: kept ones, or new.
    pub fn take(
        &self,
        ctx: &Arc<GpuContext>,
        kind: ViewKind,
        size: (u32, u32),
        name: &str,
    ) -> Result<PooledTargets<'_>> {
        let kept = {
            let mut free = self.free.lock().unwrap_or_else(|p| p.into_inner());
            match free.iter().rposition(|(k, s, _)| (*k, *s) == (kind, size)) {
                Some(i) => Some(free.remove(i).2),
                None => {
                    // Views of this kind at other sizes are what a new size replaces: freed
                    // first, so a batch of a new shape does not hold both.
                    free.retain(|(k, _, _)| *k != kind);
                    None
                }
            }
        };
        let targets = match kept {
            Some(targets) => targets,
            None => match ViewTargets::new(ctx, kind, size.0, size.1, name) {
                Ok(targets) => targets,
                Err(_) => {
                    // Out of memory, perhaps for what the pool holds: free it all and try once more.
                    self.free.lock().unwrap_or_else(|p| p.into_inner()).clear();
                    ViewTargets::new(ctx, kind, size.0, size.1, name)?
                }
            },
        };
        Ok(PooledTargets { pool: self, kind, size, targets: Some(targets) })
    }
}

/// Targets on loan from the pool; they go back when dropped.
pub(crate) struct PooledTargets<'a> {
    pool: &'a TargetPool,
    kind: ViewKind,
    size: (u32, u32),
    targets: Option<ViewTargets>,
}

impl std::ops::Deref for PooledTargets<'_> {
    type Target = ViewTargets;
    fn deref(&self) -> &ViewTargets {
        self.targets.as_ref().expect("held until dropped")
    }
}

impl Drop for PooledTargets<'_> {
    fn drop(&mut self) {
        if let Some(targets) = self.targets.take() {
            let mut free = self.pool.free.lock().unwrap_or_else(|p| p.into_inner());
            free.push((self.kind, self.size, targets));
            if free.len() > KEPT {
                free.remove(0);
            }
        }
    }
}
