//! Surfaces of a model that names none: edge-adjacent triangles whose planes agree are
//! merged (union-find over shared edges), so a box read from an ungrouped OBJ gets its six
//! faces and a tessellated curved patch gets one surface per facet.
//!
//! Two triangles sharing an edge are coplanar when their unit normals differ by less than
//! [`COPLANAR_ANGLE_TOLERANCE`] radians (either orientation) and the far corner of each lies
//! within [`COPLANAR_DISTANCE_TOLERANCE`] × the model's bounding radius of the other's plane.
//! Vertices are welded by exact position first, since OBJ files often repeat a corner per face.

use super::adjacency::weld_vertices;
use super::Mesh;
use glam::DVec3;
use std::collections::HashMap;

/// Largest angle between the normals of two merged triangles, in radians (about 0.06°).
pub const COPLANAR_ANGLE_TOLERANCE: f64 = 1e-3;
/// Largest distance from a triangle's corner to its neighbour's plane, relative to the
/// model's bounding radius.
pub const COPLANAR_DISTANCE_TOLERANCE: f64 = 1e-6;

/// Replaces the mesh's surfaces by the coplanar patches of its triangles, named
/// `face1`, `face2`, … in order of their first triangle.
pub fn merge_coplanar_surfaces(mut mesh: Mesh) -> Mesh {
    let welded = weld_vertices(&mesh.positions);
    let tris: Vec<[u32; 3]> = mesh.triangles.iter().map(|t| t.map(|v| welded[v as usize])).collect();
    let normals: Vec<DVec3> = mesh
        .triangles
        .iter()
        .map(|t| {
            let [a, b, c] = t.map(|v| mesh.vertex(v));
            (b - a).cross(c - a).normalize()
        })
        .collect();
    let (_, radius) = mesh.bounding_sphere();
    let max_distance = COPLANAR_DISTANCE_TOLERANCE * radius.max(f64::MIN_POSITIVE);

    let mut parent: Vec<usize> = (0..tris.len()).collect();
    let mut edge_owner: HashMap<(u32, u32), usize> = HashMap::new();
    for (t, tri) in tris.iter().enumerate() {
        for k in 0..3 {
            let (a, b) = (tri[k], tri[(k + 1) % 3]);
            let edge = (a.min(b), a.max(b));
            match edge_owner.get(&edge) {
                Some(&other) => {
                    if coplanar(&mesh, &normals, t, other, max_distance) {
                        union(&mut parent, t, other);
                    }
                }
                None => {
                    edge_owner.insert(edge, t);
                }
            }
        }
    }

    let mut surface_of_root: HashMap<usize, u32> = HashMap::new();
    mesh.triangle_surfaces = (0..tris.len())
        .map(|t| {
            let root = find(&mut parent, t);
            let next = surface_of_root.len() as u32 + 1;
            *surface_of_root.entry(root).or_insert(next)
        })
        .collect();
    mesh.surface_names = (1..=surface_of_root.len()).map(|i| format!("face{i}")).collect();
    // The caller knows the triangles' materials (obj.rs).
    mesh.surface_reflectivity = vec![None; surface_of_root.len()];
    mesh
}

fn coplanar(mesh: &Mesh, normals: &[DVec3], a: usize, b: usize, max_distance: f64) -> bool {
    let (na, nb) = (normals[a], normals[b]);
    if na.cross(nb).length() > COPLANAR_ANGLE_TOLERANCE.sin() {
        return false;
    }
    let off_plane = |t: usize, n: DVec3, origin: DVec3| {
        mesh.triangles[t].iter().map(|&v| (mesh.vertex(v) - origin).dot(n).abs()).fold(0.0, f64::max)
    };
    let origin_a = mesh.vertex(mesh.triangles[a][0]);
    let origin_b = mesh.vertex(mesh.triangles[b][0]);
    off_plane(b, na, origin_a) <= max_distance && off_plane(a, nb, origin_b) <= max_distance
}

fn find(parent: &mut [usize], mut i: usize) -> usize {
    while parent[i] != i {
        parent[i] = parent[parent[i]];
        i = parent[i];
    }
    i
}

fn union(parent: &mut [usize], a: usize, b: usize) {
    let (ra, rb) = (find(parent, a), find(parent, b));
    parent[ra.max(rb)] = ra.min(rb);
}
