//! A mesh uploaded once into device-local memory: vertex positions (offsets from the mesh's
//! origin, `Mesh::origin`) and triangle indices (the graphics pipeline's vertex input), a
//! record of each triangle's corners and unit normal, per-triangle surface ids and edge links,
//! and which triangles lie on the mesh's convex hull (found on first use: only the depth
//! test reads them, and a dense mesh's hull takes a large share of a render's time); and
//! whether the mesh bounds a solid, found once here, so that both rasterizers may skip the
//! triangles facing away. The shaders read them through buffer device addresses, indexed by
//! triangle (gl_PrimitiveID in the fragment shader), to label the pixel and evaluate its
//! triangle's plane exactly.
//!
//! The corners are stored a triangle at a time, as well as indexed: a shader reaching a
//! triangle's corner then reads it directly, not an index first and then the position it
//! names. The depth test's walks, which read a corner at every step, gain most from it; it
//! costs 36 bytes a triangle. With the normal they make one 48-byte record
//! ([`TriangleRecord`]), which the compute rasterizer's shaders read in 64-bit words, half as
//! many loads (shaders/raster/triangle_words.glsl).
//!
//! The normals are computed here, once, in f64 from the (f32) corners: a sliver triangle's
//! edges are nearly parallel, and their cross product in f32, per fragment, lost most of its
//! digits (a box cut into aspect-1000 strips showed shadow on a face nothing can shadow).

use crate::error::{Error, Result};
use crate::gpu::shaders::matches_shader_struct;
use crate::gpu::{Buffer, GpuContext};
use crate::mesh::{hull_face_bits, hull_tolerance, Mesh, Solidity, MAX_LINKED_TRIANGLES};
use ash::vk;
use glam::DVec3;
use std::sync::{Arc, OnceLock, Weak};

pub struct GpuMesh {
    pub(crate) vertices: Buffer,
    pub(crate) indices: Buffer,
    /// Each triangle's [`TriangleRecord`].
    pub(crate) triangles: Buffer,
    pub(crate) surface_ids: Buffer,
    /// What lies across each triangle's three edges (`Mesh::edge_links`).
    pub(crate) links: Buffer,
    /// Which triangles lie on the mesh's convex hull ([`GpuMesh::hull_faces`]), found on
    /// first use (`None` where it has none)...
    hull: OnceLock<Option<HullFaces>>,
    /// ...from the mesh this was uploaded from, held weakly (a cache of uploads must not keep
    /// its models alive), on this device.
    mesh: Weak<Mesh>,
    ctx: Arc<GpuContext>,
    pub(crate) index_count: u32,
    /// Whether the mesh bounds a solid, and which way its normals point.
    pub(crate) solidity: Solidity,
    /// Its longest edge, in model units: no triangle's projection spans more, in any view
    /// (orthographic), which tells the compute rasterizer whether its boxes fit one tile.
    pub(crate) longest_edge: f64,
    /// The model-frame point the stored positions are offsets from (`Mesh::origin`): each
    /// draw folds it into its pose, in f64.
    pub(crate) origin: DVec3,
    /// The box holding every vertex, model frame (`Mesh::bounding_box`): what a rig's
    /// directional witnesses' images are planned over (src/render/pinhole/job.rs).
    pub(crate) bounding_box: [DVec3; 2],
}

/// Which triangles of a mesh lie on its convex hull, facing out, a bit each
/// (`mesh::hull_face_bits`), and how far in front of such a face a vertex may lie, model units
/// (`mesh::hull_tolerance`): the depth test skips its walks from those faces.
pub(crate) struct HullFaces {
    pub bits: Buffer,
    pub tolerance: f32,
}

impl GpuMesh {
    /// Uploads `mesh`, which the GPU copy refers back to (weakly) for what it finds on first
    /// use.
    pub fn upload(ctx: &Arc<GpuContext>, mesh: &Arc<Mesh>) -> Result<Self> {
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
        let records: Vec<TriangleRecord> = mesh
            .triangles
            .iter()
            .zip(unit_normals(mesh))
            .map(|(corners, normal)| TriangleRecord { corner: corners.map(|v| mesh.positions[v as usize]), normal })
            .collect();
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
            triangles: Buffer::device_local_with_data(
                ctx,
                vk::BufferUsageFlags::STORAGE_BUFFER,
                &records,
                &format!("{name} triangles"),
            )?,
            surface_ids: Buffer::device_local_with_data(
                ctx,
                vk::BufferUsageFlags::STORAGE_BUFFER,
                &mesh.triangle_surfaces,
                &format!("{name} surface ids"),
            )?,
            links: Buffer::device_local_with_data(
                ctx,
                vk::BufferUsageFlags::STORAGE_BUFFER,
                &links,
                &format!("{name} edge links"),
            )?,
            hull: OnceLock::new(),
            mesh: Arc::downgrade(mesh),
            ctx: ctx.clone(),
            index_count: indices.len() as u32,
            solidity: mesh.solidity_with(&links),
            longest_edge: longest_edge(mesh),
            origin: mesh.origin,
            bounding_box: mesh.bounding_box(),
        })
    }
}

impl GpuMesh {
    /// The mesh's hull faces, found and uploaded on the first call: `None` where it has none
    /// (`mesh::hull_face_bits`: no hull, or one the library could not build), where its mesh
    /// is gone, or where the upload failed. The depth test then walks from every face, which
    /// gives the same answers more slowly; a device that failed the upload fails the work
    /// that follows it with its own error.
    pub(crate) fn hull_faces(&self) -> Option<&HullFaces> {
        self.hull
            .get_or_init(|| {
                let mesh = self.mesh.upgrade()?;
                let bits = hull_face_bits(&mesh);
                if bits.iter().all(|&word| word == 0) {
                    return None;
                }
                let usage = vk::BufferUsageFlags::STORAGE_BUFFER;
                let name = format!("{} hull faces", mesh.name);
                let bits = Buffer::device_local_with_data(&self.ctx, usage, &bits, &name).ok()?;
                Some(HullFaces { bits, tolerance: hull_tolerance(&mesh) as f32 })
            })
            .as_ref()
    }
}

/// The longest edge of the mesh's triangles, in f64 from their f32 corners.
fn longest_edge(mesh: &Mesh) -> f64 {
    mesh.triangles
        .iter()
        .flat_map(|t| (0..3).map(move |k| mesh.vertex(t[k]).distance(mesh.vertex(t[(k + 1) % 3]))))
        .fold(0.0, f64::max)
}

/// A triangle as the shaders read it (`TriangleRecord` in shaders/raster/draw.glsl, and as six 64-bit
/// words in shaders/raster/triangle_words.glsl): its corners' xyz, then its unit normal's (model
/// frame), twelve floats. 48 bytes, so that each record starts on 8 bytes.
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct TriangleRecord {
    corner: [[f32; 3]; 3],
    normal: [f32; 3],
}

matches_shader_struct!(TriangleRecord, TriangleRecord { corner, normal });

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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::builtin_mesh;

    #[test]
    fn a_meshs_longest_edge_is_its_longest_side_or_diagonal() {
        // The unit cube's triangles have sides of 1 and face diagonals of √2.
        assert_eq!(longest_edge(&builtin_mesh("builtin:box").unwrap()), 2f64.sqrt());
        // A square plate of side 4: its two triangles share the diagonal 4√2.
        assert!((longest_edge(&builtin_mesh("builtin:plane:4").unwrap()) - 4.0 * 2f64.sqrt()).abs() < 1e-12);
    }
}
