//! A mesh uploaded once into device-local memory: vertex positions and triangle indices (the
//! graphics pipeline's vertex input), each triangle's corners, per-triangle surface ids, unit
//! normals and edge links; and whether the mesh bounds a solid, found once here, so that both
//! rasterizers may skip the triangles facing away. The shaders read them through buffer
//! device addresses, indexed by triangle (gl_PrimitiveID in the fragment shader), to label the
//! pixel and evaluate its triangle's plane exactly.
//!
//! The corners are stored a triangle at a time, as well as indexed: a shader reaching a
//! triangle's corner then reads it directly, not an index first and then the position it
//! names. The depth test's walks read a corner at every step, and took 15% less time
//! (dense sphere, 256²: 22.7–23.7 → 19.3–20.4 ms), for 36 bytes a triangle.
//!
//! The normals are computed here, once, in f64 from the (f32) corners: a sliver triangle's
//! edges are nearly parallel, and their cross product in f32, per fragment, lost most of its
//! digits (a box cut into aspect-1000 strips showed shadow on a face nothing can shadow).

use crate::error::{Error, Result};
use crate::gpu::{Buffer, GpuContext};
use crate::mesh::{Mesh, Solidity, MAX_LINKED_TRIANGLES};
use ash::vk;
use std::sync::Arc;

pub struct GpuMesh {
    pub(crate) vertices: Buffer,
    pub(crate) indices: Buffer,
    /// xyz of each triangle's three corners, nine floats a triangle.
    pub(crate) corners: Buffer,
    pub(crate) surface_ids: Buffer,
    /// xyz of each triangle's unit normal (model frame), three floats a triangle.
    pub(crate) normals: Buffer,
    /// What lies across each triangle's three edges (`Mesh::edge_links`).
    pub(crate) links: Buffer,
    pub(crate) index_count: u32,
    /// Whether the mesh bounds a solid, and which way its normals point.
    pub(crate) solidity: Solidity,
}

impl GpuMesh {
    pub fn upload(ctx: &Arc<GpuContext>, mesh: &Mesh) -> Result<Self> {
        let name = &mesh.name;
        let indices: Vec<u32> = mesh.triangles.iter().flatten().copied().collect();
        if mesh.triangles.len() > MAX_LINKED_TRIANGLES {
            return Err(Error::Mesh {
                name: name.clone(),
                reason: format!(
                    "it has {} triangles; at most {MAX_LINKED_TRIANGLES} can be rendered",
                    mesh.triangles.len()
                ),
            });
        }
        let links = mesh.edge_links();
        let corners: Vec<[f32; 3]> = indices.iter().map(|&v| mesh.positions[v as usize]).collect();
        Ok(Self {
            vertices: Buffer::device_local_with_data(
                ctx,
                vk::BufferUsageFlags::VERTEX_BUFFER,
                &mesh.positions,
                &format!("{name} vertices"),
            )?,
            indices: Buffer::device_local_with_data(
                ctx,
                vk::BufferUsageFlags::INDEX_BUFFER,
                &indices,
                &format!("{name} indices"),
            )?,
            corners: Buffer::device_local_with_data(
                ctx,
                vk::BufferUsageFlags::STORAGE_BUFFER,
                &corners,
                &format!("{name} corners"),
            )?,
            surface_ids: Buffer::device_local_with_data(
                ctx,
                vk::BufferUsageFlags::STORAGE_BUFFER,
                &mesh.triangle_surfaces,
                &format!("{name} surface ids"),
            )?,
            normals: Buffer::device_local_with_data(
                ctx,
                vk::BufferUsageFlags::STORAGE_BUFFER,
                &unit_normals(mesh),
                &format!("{name} normals"),
            )?,
            links: Buffer::device_local_with_data(
                ctx,
                vk::BufferUsageFlags::STORAGE_BUFFER,
                &links,
                &format!("{name} edge links"),
            )?,
            index_count: indices.len() as u32,
            solidity: mesh.solidity_with(&links),
        })
    }
}

/// Each triangle's unit normal (counter-clockwise winding), from its corners in f64.
fn unit_normals(mesh: &Mesh) -> Vec<[f32; 3]> {
    mesh.triangles
        .iter()
        .map(|&[a, b, c]| {
            let (a, b, c) = (mesh.vertex(a), mesh.vertex(b), mesh.vertex(c));
            let n = (b - a).cross(c - a).normalize();
            [n.x as f32, n.y as f32, n.z as f32]
        })
        .collect()
}
