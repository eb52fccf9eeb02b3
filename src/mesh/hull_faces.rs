//! Which triangles of a mesh lie on its convex hull, facing out: every vertex of the mesh lies
//! on or behind the triangle's plane, as its normal (counter-clockwise winding) points.
//!
//! Why: a point on such a face, seen from its front, has nothing of its own model in front of
//! the face's plane, so nothing of that model can lie between it and any witness the face
//! turns toward. The depth test's walks over the surfaces a witness saw (the costliest part of
//! shadow mode `depth`) can only confirm it; where the views hold that model alone, as a
//! verified hypothesis's do, the test skips them (shaders/stages/shadow_mask.comp). Boxes,
//! cylinders, spheres and most outer faces of a machined part are such faces.
//!
//! The hull is parry3d's (quickhull); each face's plane is then checked against the hull's
//! vertex farthest along its normal, found by climbing the hull's edges (on a convex polytope
//! a vertex no neighbour beats is the farthest), from where the previous face's climb ended.
//! A face counts only if no vertex lies more than [`HULL_TOLERANCE`] of the mesh's extent in
//! front of its plane (f32 rounding of the positions). A mesh the
//! hull cannot be built for (a failure in the library), or of more than [`MAX_HULL_VERTICES`]
//! distinct vertices, has no hull faces: the test then walks as before.

use crate::mesh::Mesh;
use glam::DVec3;
use parry3d_f64::math::Vector3;
use parry3d_f64::transformation::try_convex_hull;

/// Distinct vertices beyond which no hull is built: its time and memory (a few hundred bytes
/// a vertex) grow with them (on the 2-core development machine, a sphere of 51k vertices, all
/// on its hull, takes a quarter of a second, and one of 244k four seconds), and such a mesh is
/// tested without the shortcut.
pub const MAX_HULL_VERTICES: usize = 1 << 17;

/// How far in front of a face's plane, relative to the mesh's bounding-box diagonal, a vertex
/// may lie and the face still count: half of f32's epsilon, for the f32 rounding of the
/// stored positions, which breaks the planarity of a tessellated sphere's quads by up to a
/// quarter of it (the built-in spheres of 24 to 320 segments). The depth test takes the
/// shortcut only where the camera's ray leaves the face steeply enough that so small a rise
/// stays well below its bias (shaders/stages/shadow_mask.comp).
pub const HULL_TOLERANCE: f64 = 0.5 * f32::EPSILON as f64;

/// [`HULL_TOLERANCE`] for `mesh`, in its model units.
pub fn hull_tolerance(mesh: &Mesh) -> f64 {
    let [lo, hi] = mesh.bounding_box();
    HULL_TOLERANCE * (hi - lo).length()
}

/// Bit t % 32 of word t / 32 set where triangle t lies on the mesh's convex hull, facing out.
pub fn hull_face_bits(mesh: &Mesh) -> Vec<u32> {
    let mut bits = vec![0u32; mesh.triangles.len().div_ceil(32)];
    let Some(hull) = Hull::of(mesh) else {
        return bits;
    };
    let tolerance = hull_tolerance(mesh);
    let mut start = 0;
    for (t, &[a, b, c]) in mesh.triangles.iter().enumerate() {
        let (a, b, c) = (offset(mesh, a), offset(mesh, b), offset(mesh, c));
        let normal = (b - a).cross(c - a).normalize_or_zero();
        if normal == DVec3::ZERO {
            continue;
        }
        let farthest;
        (farthest, start) = hull.farthest_along(normal, start);
        if farthest - normal.dot(a) <= tolerance {
            bits[t / 32] |= 1 << (t % 32);
        }
    }
    bits
}

/// Vertex v as its offset from the mesh's origin: the hull and the planes are found in the
/// frame the positions are stored in, where their digits are.
fn offset(mesh: &Mesh, v: u32) -> DVec3 {
    DVec3::from(mesh.positions[v as usize].map(f64::from))
}

/// A convex hull's vertices and which of them share an edge.
struct Hull {
    vertices: Vec<DVec3>,
    neighbours: Vec<Vec<u32>>,
}

impl Hull {
    fn of(mesh: &Mesh) -> Option<Hull> {
        // Each position once: a mesh may repeat its corners triangle by triangle.
        let mut distinct: Vec<[u32; 3]> = mesh.positions.iter().map(|p| p.map(f32::to_bits)).collect();
        distinct.sort_unstable();
        distinct.dedup();
        if distinct.len() < 4 || distinct.len() > MAX_HULL_VERTICES {
            return None;
        }
        let points: Vec<Vector3> = distinct
            .iter()
            .map(|bits| bits.map(|b| f64::from(f32::from_bits(b))))
            .map(|[x, y, z]| Vector3::new(x, y, z))
            .collect();
        // The library asserts its own invariants: a failure there is a mesh without hull faces.
        let (vertices, triangles) = std::panic::catch_unwind(|| try_convex_hull(&points)).ok()?.ok()?;
        if triangles.is_empty() {
            return None;
        }
        let mut neighbours = vec![Vec::new(); vertices.len()];
        for triangle in &triangles {
            for k in 0..3 {
                let (from, to) = (triangle[k], triangle[(k + 1) % 3]);
                neighbours.get_mut(from as usize)?.push(to);
                neighbours.get_mut(to as usize)?.push(from);
            }
        }
        for list in &mut neighbours {
            list.sort_unstable();
            list.dedup();
        }
        let vertices = vertices.iter().map(|p| DVec3::new(p.x, p.y, p.z)).collect();
        Some(Hull { vertices, neighbours })
    }

    /// The greatest `direction · v` over the hull's vertices, and the vertex that has it,
    /// climbing from vertex `start`: each step moves to a neighbour farther along, so it ends.
    fn farthest_along(&self, direction: DVec3, start: usize) -> (f64, usize) {
        let mut at = start;
        let mut best = direction.dot(self.vertices[at]);
        loop {
            let next = self.neighbours[at]
                .iter()
                .map(|&w| (direction.dot(self.vertices[w as usize]), w as usize))
                .fold((best, at), |held, candidate| if candidate.0 > held.0 { candidate } else { held });
            if next.1 == at {
                return (best, at);
            }
            (best, at) = next;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::builtin_mesh;
    use rand::{Rng, SeedableRng};

    /// Brute force: every vertex against every triangle's plane.
    fn reference_bits(mesh: &Mesh) -> Vec<bool> {
        let tolerance = hull_tolerance(mesh);
        mesh.triangles
            .iter()
            .map(|&[a, b, c]| {
                let (a, b, c) = (offset(mesh, a), offset(mesh, b), offset(mesh, c));
                let normal = (b - a).cross(c - a).normalize_or_zero();
                normal != DVec3::ZERO
                    && (0..mesh.positions.len() as u32).all(|v| normal.dot(offset(mesh, v) - a) <= tolerance)
            })
            .collect()
    }

    fn bits_as_bools(mesh: &Mesh) -> Vec<bool> {
        let bits = hull_face_bits(mesh);
        (0..mesh.triangles.len()).map(|t| bits[t / 32] >> (t % 32) & 1 == 1).collect()
    }

    #[test]
    fn convex_builtins_are_all_hull_faces() {
        for name in ["builtin:box", "builtin:sphere:24", "builtin:cylinder:32"] {
            let mesh = builtin_mesh(name).unwrap();
            let bits = bits_as_bools(&mesh);
            assert!(bits.iter().all(|&b| b), "{name}: {} of {} faces", bits.iter().filter(|&&b| b).count(), bits.len());
        }
    }

    #[test]
    fn a_box_turned_inside_out_has_none() {
        let mut mesh = builtin_mesh("builtin:box").unwrap();
        for t in &mut mesh.triangles {
            t.swap(1, 2);
        }
        assert!(bits_as_bools(&mesh).iter().all(|&b| !b));
    }

    /// Nothing lies in front of a flat mesh, on either side.
    #[test]
    fn a_flat_mesh_is_all_hull_faces() {
        let mut mesh = builtin_mesh("builtin:plane:2").unwrap();
        assert!(bits_as_bools(&mesh).iter().all(|&b| b));
        for t in &mut mesh.triangles {
            t.swap(1, 2);
        }
        assert!(bits_as_bools(&mesh).iter().all(|&b| b));
    }

    /// Concave meshes (an L of boxes, a terrain of random heights) against brute force: the
    /// faces in a notch or a valley are not on the hull.
    #[test]
    fn concave_meshes_match_brute_force() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
        let (mut on_hull, mut off_hull) = (0, 0);
        for trial in 0..20 {
            let n = 6 + trial % 5;
            let mut positions = Vec::new();
            for i in 0..n {
                for j in 0..n {
                    positions.push([i as f64, j as f64, rng.gen_range(0.0..2.0)]);
                }
            }
            // The terrain's underside: one vertex below its middle closes it into a cone.
            positions.push([(n - 1) as f64 / 2.0, (n - 1) as f64 / 2.0, -5.0]);
            let bottom = (n * n) as u32;
            let index = |i: usize, j: usize| (i * n + j) as u32;
            let mut triangles = Vec::new();
            for i in 0..n - 1 {
                for j in 0..n - 1 {
                    triangles.push([index(i, j), index(i + 1, j), index(i + 1, j + 1)]);
                    triangles.push([index(i, j), index(i + 1, j + 1), index(i, j + 1)]);
                }
            }
            for k in 0..n - 1 {
                triangles.push([index(k + 1, 0), index(k, 0), bottom]);
                triangles.push([index(n - 1, k + 1), index(n - 1, k), bottom]);
                triangles.push([index(k, n - 1), index(k + 1, n - 1), bottom]);
                triangles.push([index(0, k), index(0, k + 1), bottom]);
            }
            let surfaces = vec![1; triangles.len()];
            let mesh = Mesh::new("terrain", positions, triangles, surfaces, vec!["s".into()]).unwrap();
            let expected = reference_bits(&mesh);
            assert_eq!(bits_as_bools(&mesh), expected, "trial {trial}");
            on_hull += expected.iter().filter(|&&b| b).count();
            off_hull += expected.iter().filter(|&&b| !b).count();
        }
        assert!(on_hull > 50 && off_hull > 50, "{on_hull} faces on the hull, {off_hull} off it");
    }

    #[test]
    fn the_dense_sphere_is_whole() {
        let mesh = builtin_mesh("builtin:sphere:320").unwrap();
        let bits = bits_as_bools(&mesh);
        assert!(bits.iter().all(|&b| b));
    }
}
