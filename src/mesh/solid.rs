//! Whether a mesh bounds a solid, and which way its normals point: what back-face culling
//! needs to know (src/render/draw.rs for the graphics pipeline, src/render/compute_raster.rs).
//!
//! A camera ray first meets a solid where it enters it, through a triangle whose outward
//! normal faces the camera; a triangle facing away can be first only where it meets one that
//! faces the camera, at the silhouette. So the triangles facing away can be skipped, but only
//! when the mesh really bounds a solid: an open mesh (a sheet, a part with a missing face)
//! shows its back faces through the opening, and a mesh wound inconsistently has no "away".
//! The test is strict: every edge shared by exactly two triangles that run it in opposite
//! directions (vertices matched by position, as adjacency.rs matches them), and every
//! connected shell enclosing a volume of the same, clearly non-zero sign. Anything else is
//! [`Solidity::Open`] and is never culled. (A shell that passes through itself, turning part
//! of itself inside out, passes this test and would lose the inside-out part; such a surface
//! bounds no solid, and finding it would cost a triangle-triangle intersection test.)

use super::adjacency::weld_vertices;
use super::{Mesh, NO_NEIGHBOUR};
use glam::DVec3;

/// What a mesh bounds, as [`Mesh::solidity`] finds it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Solidity {
    /// Not a closed, consistently wound surface (or one enclosing no volume): every triangle
    /// may be seen.
    Open,
    /// Closed, consistently wound, normals (counter-clockwise winding) pointing out: triangles
    /// whose normal faces away from the camera are never the first hit.
    Outward,
    /// As `Outward`, wound the other way: normals point in.
    Inward,
}

/// A shell's volume must exceed this fraction of its bounding box's volume to have a sign
/// (a flat, double-sided sheet is closed and consistently wound but encloses nothing).
const MIN_RELATIVE_VOLUME: f64 = 1e-9;

impl Mesh {
    /// Whether this mesh bounds a solid.
    pub fn solidity(&self) -> Solidity {
        self.solidity_with(&self.triangle_neighbours())
    }

    /// As [`Mesh::solidity`], given the mesh's [`Mesh::triangle_neighbours`] (the upload has
    /// them already).
    pub(crate) fn solidity_with(&self, neighbours: &[[u32; 3]]) -> Solidity {
        debug_assert_eq!(neighbours.len(), self.triangles.len());
        if !self.is_closed_and_consistent() {
            return Solidity::Open;
        }
        let mut sign = 0.0;
        for shell in shells(neighbours) {
            let corners = |t: u32| self.triangles[t as usize].map(|v| self.vertex(v));
            // Relative to a corner of the shell, so that a shell far from the origin keeps its digits.
            let origin = corners(shell[0])[0];
            let (mut lo, mut hi) = (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY));
            let mut volume = 0.0;
            for &t in &shell {
                let [a, b, c] = corners(t).map(|p| p - origin);
                volume += a.dot(b.cross(c)) / 6.0;
                for p in [a, b, c] {
                    (lo, hi) = (lo.min(p), hi.max(p));
                }
            }
            let extent = hi - lo;
            if volume.abs() <= MIN_RELATIVE_VOLUME * extent.x * extent.y * extent.z || volume * sign < 0.0 {
                return Solidity::Open;
            }
            sign = volume.signum();
        }
        match sign > 0.0 {
            true => Solidity::Outward,
            false => Solidity::Inward,
        }
    }

    /// Every edge (welded) joins two points and is run once in each direction, so by two
    /// different triangles.
    fn is_closed_and_consistent(&self) -> bool {
        let welded = weld_vertices(&self.positions);
        let directed = |a: u32, b: u32| (u64::from(welded[a as usize]) << 32) | u64::from(welded[b as usize]);
        let mut edges: Vec<u64> =
            self.triangles.iter().flat_map(|&[a, b, c]| [directed(a, b), directed(b, c), directed(c, a)]).collect();
        edges.sort_unstable();
        let reversed = |edge: u64| edge.rotate_left(32);
        let joins_two_points = edges.iter().all(|&edge| reversed(edge) != edge);
        let unique = edges.windows(2).all(|pair| pair[0] != pair[1]);
        joins_two_points && unique && edges.iter().all(|&edge| edges.binary_search(&reversed(edge)).is_ok())
    }
}

/// The triangles of each connected shell, across linked edges.
fn shells(neighbours: &[[u32; 3]]) -> Vec<Vec<u32>> {
    let mut seen = vec![false; neighbours.len()];
    let mut shells = Vec::new();
    for start in 0..neighbours.len() {
        if seen[start] {
            continue;
        }
        seen[start] = true;
        let mut shell = vec![start as u32];
        let mut next = 0;
        while next < shell.len() {
            for n in neighbours[shell[next] as usize] {
                if n != NO_NEIGHBOUR && !seen[n as usize] {
                    seen[n as usize] = true;
                    shell.push(n);
                }
            }
            next += 1;
        }
        shells.push(shell);
    }
    shells
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::builtin_mesh;

    fn solidity(mesh: &Mesh) -> Solidity {
        mesh.solidity()
    }

    /// Both meshes' triangles in one mesh.
    fn join(a: &Mesh, b: &Mesh) -> Mesh {
        let offset = a.positions.len() as u32;
        let positions = a.positions.iter().chain(&b.positions).copied().collect();
        let triangles: Vec<[u32; 3]> =
            a.triangles.iter().copied().chain(b.triangles.iter().map(|t| t.map(|v| v + offset))).collect();
        let surfaces = vec![1; triangles.len()];
        Mesh::new("joined", positions, triangles, surfaces, vec!["s".into()]).unwrap()
    }

    fn moved(mut mesh: Mesh, by: [f32; 3], scale: f32) -> Mesh {
        for p in &mut mesh.positions {
            *p = [0, 1, 2].map(|k| p[k] * scale + by[k]);
        }
        mesh
    }

    fn inside_out(mut mesh: Mesh) -> Mesh {
        for tri in &mut mesh.triangles {
            tri.swap(1, 2);
        }
        mesh
    }

    /// The unit cube's 12 triangles, counter-clockwise seen from outside.
    fn cube() -> Mesh {
        let positions = (0..8).map(|i| [(i & 1) as f32, ((i >> 1) & 1) as f32, ((i >> 2) & 1) as f32]).collect();
        let quads = [[0, 2, 3, 1], [4, 5, 7, 6], [0, 1, 5, 4], [2, 6, 7, 3], [0, 4, 6, 2], [1, 3, 7, 5]];
        let triangles: Vec<[u32; 3]> = quads.iter().flat_map(|&[a, b, c, d]| [[a, b, c], [a, c, d]]).collect();
        Mesh::new("cube", positions, triangles, vec![1; 12], vec!["s".into()]).unwrap()
    }

    #[test]
    fn a_cube_wound_outward_or_inward_bounds_a_solid() {
        assert_eq!(solidity(&cube()), Solidity::Outward);
        assert_eq!(solidity(&inside_out(cube())), Solidity::Inward);
    }

    #[test]
    fn an_open_or_inconsistent_cube_is_open() {
        let mut open = cube();
        open.triangles.pop();
        open.triangle_surfaces.pop();
        assert_eq!(solidity(&open), Solidity::Open);
        let mut flipped = cube();
        flipped.triangles[0].swap(1, 2);
        assert_eq!(solidity(&flipped), Solidity::Open);
    }

    #[test]
    fn shells_count_only_when_all_wound_the_same_way() {
        let apart = moved(cube(), [3.0, 0.0, 0.0], 1.0);
        assert_eq!(solidity(&join(&cube(), &apart)), Solidity::Outward);
        assert_eq!(solidity(&join(&cube(), &inside_out(apart))), Solidity::Open);
        // A hollow cube, its cavity wound inward: the camera never sees the cavity, but the
        // shells' volumes differ in sign, and the rule keeps it whole.
        let cavity = inside_out(moved(cube(), [0.25, 0.25, 0.25], 0.5));
        assert_eq!(solidity(&join(&cube(), &cavity)), Solidity::Open);
    }

    #[test]
    fn a_double_sided_sheet_encloses_nothing() {
        let positions = vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
        let sheet = Mesh::new("sheet", positions, vec![[0, 1, 2], [0, 2, 1]], vec![1, 1], vec!["s".into()]).unwrap();
        assert_eq!(solidity(&sheet), Solidity::Open);
    }

    #[test]
    fn the_builtin_solids_are_wound_outward() {
        for name in ["builtin:box", "builtin:cylinder", "builtin:sphere", "builtin:sphere:320"] {
            let mesh = builtin_mesh(name).unwrap();
            assert_eq!(solidity(&mesh), Solidity::Outward, "{name}");
        }
        // The stepped block's sides end where its bottom has no corner (T-junctions), and its
        // +y side is wound like its −y side: it is drawn whole.
        assert_eq!(solidity(&builtin_mesh("builtin:step").unwrap()), Solidity::Open);
        assert_eq!(solidity(&builtin_mesh("builtin:plane").unwrap()), Solidity::Open);
    }
}
