//! A mesh uploaded once into device-local memory: vertex positions, triangle indices and
//! per-triangle surface ids.
//! The fragment shader reads all three through buffer device addresses, indexed by
//! gl_PrimitiveID, to label the pixel and evaluate its triangle's plane exactly.

use crate::error::Result;
use crate::gpu::{Buffer, GpuContext};
use crate::mesh::Mesh;
use ash::vk;
use std::sync::Arc;

pub struct GpuMesh {
    pub(crate) vertices: Buffer,
    pub(crate) indices: Buffer,
    pub(crate) surface_ids: Buffer,
    pub(crate) index_count: u32,
}

impl GpuMesh {
    pub fn upload(ctx: &Arc<GpuContext>, mesh: &Mesh) -> Result<Self> {
        let name = &mesh.name;
        let indices: Vec<u32> = mesh.triangles.iter().flatten().copied().collect();
        Ok(Self {
            vertices: Buffer::device_local_with_data(
                ctx,
                vk::BufferUsageFlags::VERTEX_BUFFER | vk::BufferUsageFlags::STORAGE_BUFFER,
                &mesh.positions,
                &format!("{name} vertices"),
            )?,
            indices: Buffer::device_local_with_data(
                ctx,
                vk::BufferUsageFlags::INDEX_BUFFER | vk::BufferUsageFlags::STORAGE_BUFFER,
                &indices,
                &format!("{name} indices"),
            )?,
            surface_ids: Buffer::device_local_with_data(
                ctx,
                vk::BufferUsageFlags::STORAGE_BUFFER,
                &mesh.triangle_surfaces,
                &format!("{name} surface ids"),
            )?,
            index_count: indices.len() as u32,
        })
    }
}
