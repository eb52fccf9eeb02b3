//! Meshes uploaded once per model: a renderer keeps each mesh it has drawn on the GPU for as
//! long as the model (its `Arc<Mesh>`) lives, so rendering the same scene, or scenes sharing
//! models, again uploads nothing. Entries are keyed by the model's address and checked
//! against a weak reference, so a freed model's address reused by another is never mistaken
//! for it; dead entries are dropped on the next upload.

use crate::error::Result;
use crate::gpu::GpuContext;
use crate::mesh::Mesh;
use crate::render::gpu_mesh::GpuMesh;
use std::collections::HashMap;
use std::sync::{Arc, Mutex, Weak};

/// A model (weakly held, to check the address still names it) and its GPU copy.
type Entry = (Weak<Mesh>, Arc<GpuMesh>);

#[derive(Default)]
pub(crate) struct MeshCache {
    entries: Mutex<HashMap<usize, Entry>>,
}

impl MeshCache {
    /// The GPU copy of `mesh`, uploaded now if this renderer has none alive.
    pub fn get(&self, ctx: &Arc<GpuContext>, mesh: &Arc<Mesh>) -> Result<Arc<GpuMesh>> {
        let key = Arc::as_ptr(mesh) as usize;
        {
            let entries = self.entries.lock().unwrap_or_else(|p| p.into_inner());
            if let Some((model, gpu)) = entries.get(&key) {
                if model.upgrade().is_some_and(|m| Arc::ptr_eq(&m, mesh)) {
                    return Ok(gpu.clone());
                }
            }
        }
        let gpu = Arc::new(GpuMesh::upload(ctx, mesh)?);
        let mut entries = self.entries.lock().unwrap_or_else(|p| p.into_inner());
        // Models dropped since the last upload free their copies here, not on every lookup.
        entries.retain(|_, (model, _)| model.strong_count() > 0);
        entries.insert(key, (Arc::downgrade(mesh), gpu.clone()));
        Ok(gpu)
    }
}
