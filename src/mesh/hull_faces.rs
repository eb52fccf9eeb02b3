//! Which triangles of a mesh lie on its convex hull, facing out: every vertex of the mesh lies
//! on or behind the triangle's plane, as its normal (counter-clockwise winding) points.
//!
//! Why: a point on such a face, seen from its front, has nothing of its own model in front of
//! the face's plane, so nothing of that model can lie between it and any witness the face
//! turns toward. The depth test's walks over the surfaces a witness saw (the costliest part of
//! shadow mode `depth`) can only confirm it; where the views hold that model alone, as a
//! verified hypothesis's do, the test skips them (shaders/stages/shadow_mask.comp and
//! witness_mask.comp). Boxes, cylinders, spheres and most outer faces of a machined part are
//! such faces.
//!
//! The hull is parry3d's (quickhull); each face's plane is then checked against the hull's
//! vertex farthest along its normal, found by climbing the hull's edges from where the previous
//! face's climb ended (`Climb`). A face counts only if no vertex lies more than
//! [`HULL_TOLERANCE`] of the mesh's extent in front of its plane (f32 rounding of the
//! positions). A mesh whose hull cannot be built (fewer than four distinct vertices, a failure
//! in the library) or has no volume (a flat or nearly flat mesh), one of more than
//! [`MAX_HULL_VERTICES`] distinct vertices, and one whose climbs run past their budget have no
//! hull faces: the test then walks as before.

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
    let [lo, hi] = mesh.bounding_box();
    let extent = (hi - lo).length();
    let Some(hull) = Hull::of(mesh, extent) else {
        return bits;
    };
    let tolerance = hull_tolerance(mesh);
    let mut climb =
        Climb::new(&hull, tolerance / 8.0, CLIMB_STEPS_PER_ITEM * (mesh.triangles.len() + hull.vertices.len()));
    for (t, &[a, b, c]) in mesh.triangles.iter().enumerate() {
        let (a, b, c) = (offset(mesh, a), offset(mesh, b), offset(mesh, c));
        let normal = (b - a).cross(c - a).normalize_or_zero();
        if normal == DVec3::ZERO {
            continue;
        }
        let Some(farthest) = climb.farthest_along(normal) else {
            return vec![0; bits.len()];
        };
        if farthest - normal.dot(a) <= tolerance {
            bits[t / 32] |= 1 << (t % 32);
        }
    }
    bits
}

/// The neighbours a face's climb may look at, on average over the faces and the hull's
/// vertices, before the mesh is given up as having no hull faces: climbs from one face to the
/// next are short on a mesh whose faces come in order, and a plateau (a flat region of the
/// hull, many vertices of it in one plane) is crossed whole.
const CLIMB_STEPS_PER_ITEM: usize = 512;

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
    /// The hull of the mesh's vertices (`extent` its bounding box's diagonal), or None where it
    /// is not a solid: parry3d returns a flat polygon (or a segment, or a point) for points
    /// that lie nearly in a plane, leaving out the few that do not (a stud on a plate), so a
    /// hull without volume says nothing.
    fn of(mesh: &Mesh, extent: f64) -> Option<Hull> {
        // Each position once (−0 and 0 as one): a mesh may repeat its corners triangle by
        // triangle.
        let mut distinct: Vec<[u32; 3]> = mesh.positions.iter().map(|p| p.map(|c| (c + 0.0).to_bits())).collect();
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
        let vertices: Vec<DVec3> = vertices.iter().map(|p| DVec3::new(p.x, p.y, p.z)).collect();
        let corner = |i: u32| vertices.get(i as usize).copied();
        let mut six_volume = 0.0;
        let mut neighbours = vec![Vec::new(); vertices.len()];
        for triangle in &triangles {
            let [a, b, c] = [corner(triangle[0])?, corner(triangle[1])?, corner(triangle[2])?];
            six_volume += (a - vertices[0]).dot((b - vertices[0]).cross(c - vertices[0]));
            for k in 0..3 {
                let (from, to) = (triangle[k], triangle[(k + 1) % 3]);
                neighbours[from as usize].push(to);
                neighbours[to as usize].push(from);
            }
        }
        if six_volume.abs() <= 1e-9 * extent.powi(3) {
            return None;
        }
        for list in &mut neighbours {
            list.sort_unstable();
            list.dedup();
        }
        Some(Hull { vertices, neighbours })
    }
}

/// Climbs a hull toward the vertex farthest along a direction, face after face, each climb
/// starting where the last ended.
struct Climb<'h> {
    hull: &'h Hull,
    /// Values within this of each other are a plateau, crossed whole.
    tie: f64,
    /// Neighbours left to look at.
    budget: usize,
    at: usize,
    /// The vertices of the plateau being crossed, and the climb each was last reached by.
    plateau: Vec<usize>,
    reached_by: Vec<usize>,
    climbs: usize,
}

impl<'h> Climb<'h> {
    fn new(hull: &'h Hull, tie: f64, budget: usize) -> Self {
        Climb {
            hull,
            tie,
            budget,
            at: 0,
            plateau: Vec::new(),
            reached_by: vec![usize::MAX; hull.vertices.len()],
            climbs: 0,
        }
    }

    /// The greatest `direction · v` over the hull's vertices, to within `tie`, or None when
    /// the budget runs out. On a convex polytope every vertex short of the farthest has a
    /// neighbour farther along, so a climb that finds none from a whole plateau (the vertices
    /// within `tie` of where it stands, joined by edges) has found the farthest; stopping at
    /// the first vertex without a farther neighbour would stop inside a flat face of the hull
    /// turned away from the direction, at its nearest.
    fn farthest_along(&mut self, direction: DVec3) -> Option<f64> {
        let value = |v: usize| direction.dot(self.hull.vertices[v]);
        let mut best = value(self.at);
        'climb: loop {
            self.climbs += 1;
            self.plateau.clear();
            self.plateau.push(self.at);
            self.reached_by[self.at] = self.climbs;
            let mut next = 0;
            while let Some(&from) = self.plateau.get(next) {
                next += 1;
                for &w in &self.hull.neighbours[from] {
                    self.budget = self.budget.checked_sub(1)?;
                    let w = w as usize;
                    let farther = value(w);
                    if farther > best + self.tie {
                        (self.at, best) = (w, farther);
                        continue 'climb;
                    }
                    if farther >= best - self.tie && self.reached_by[w] != self.climbs {
                        self.reached_by[w] = self.climbs;
                        self.plateau.push(w);
                    }
                }
            }
            return Some(self.plateau.iter().map(|&v| value(v)).fold(best, f64::max));
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
        (0..mesh.triangles.len()).map(|t| on_hull_by_brute_force(mesh, t)).collect()
    }

    /// Brute force for one triangle: every vertex against its plane.
    fn on_hull_by_brute_force(mesh: &Mesh, t: usize) -> bool {
        let tolerance = hull_tolerance(mesh);
        let [a, b, c] = mesh.triangles[t].map(|v| offset(mesh, v));
        let normal = (b - a).cross(c - a).normalize_or_zero();
        normal != DVec3::ZERO && (0..mesh.positions.len() as u32).all(|v| normal.dot(offset(mesh, v) - a) <= tolerance)
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

    /// parry3d's hull of nearly coplanar points is a flat polygon, which says nothing.
    #[test]
    fn a_flat_mesh_has_none() {
        let mesh = builtin_mesh("builtin:plane:2").unwrap();
        assert!(bits_as_bools(&mesh).iter().all(|&b| !b));
    }

    /// A metre-wide plate of many vertices with a 1 cm stud on it: its points lie nearly in a
    /// plane, and parry3d leaves the stud out of the flat hull it makes of them. No face the
    /// stud rises in front of may count.
    #[test]
    fn a_plate_with_a_stud_marks_no_face_the_stud_rises_in_front_of() {
        let n = 200;
        let mut positions = Vec::new();
        let mut triangles = Vec::new();
        let index = |i: usize, j: usize| (i * n + j) as u32;
        for i in 0..n {
            for j in 0..n {
                positions.push([i as f64 / (n - 1) as f64, j as f64 / (n - 1) as f64, 0.0]);
            }
        }
        for i in 0..n - 1 {
            for j in 0..n - 1 {
                triangles.push([index(i, j), index(i + 1, j), index(i + 1, j + 1)]);
                triangles.push([index(i, j), index(i + 1, j + 1), index(i, j + 1)]);
            }
        }
        let stud = builtin_mesh("builtin:box").unwrap();
        let first = positions.len() as u32;
        positions.extend(
            (0..stud.positions.len() as u32).map(|v| (stud.vertex(v) * 0.01 + DVec3::new(0.5, 0.5, 0.005)).to_array()),
        );
        triangles.extend(stud.triangles.iter().map(|t| t.map(|v| v + first)));
        let surfaces = vec![1; triangles.len()];
        let mesh = Mesh::new("plate", positions, triangles, surfaces, vec!["s".into()]).unwrap();
        assert!(!on_hull_by_brute_force(&mesh, 0), "the plate's faces lie behind the stud's top");
        let bits = bits_as_bools(&mesh);
        assert!((0..bits.len()).all(|t| !bits[t] || on_hull_by_brute_force(&mesh, t)));
    }

    /// A climb that starts inside a flat face of the hull turned away from its direction sees
    /// only neighbours as near as itself; it must cross that face to reach the far vertex.
    #[test]
    fn a_climb_crosses_a_flat_face_turned_away() {
        // A square pyramid whose base has a vertex at its centre (vertex 4), joined to the
        // base's corners only; the apex (5) is 1 above.
        let vertices = vec![
            DVec3::new(-1.0, -1.0, 0.0),
            DVec3::new(1.0, -1.0, 0.0),
            DVec3::new(1.0, 1.0, 0.0),
            DVec3::new(-1.0, 1.0, 0.0),
            DVec3::ZERO,
            DVec3::new(0.0, 0.0, 1.0),
        ];
        let neighbours = vec![
            vec![1, 3, 4, 5],
            vec![0, 2, 4, 5],
            vec![1, 3, 4, 5],
            vec![0, 2, 4, 5],
            vec![0, 1, 2, 3],
            vec![0, 1, 2, 3],
        ];
        let hull = Hull { vertices, neighbours };
        let mut climb = Climb::new(&hull, 1e-12, 1000);
        climb.at = 4;
        assert_eq!(climb.farthest_along(DVec3::Z), Some(1.0));
    }

    /// Terrains of random heights closed by a cone below, against brute force: the faces in a
    /// valley are not on the hull.
    #[test]
    fn terrains_match_brute_force() {
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
