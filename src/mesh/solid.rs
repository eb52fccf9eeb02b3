//! Whether a mesh bounds a solid, and which way its normals point: what back-face culling
//! needs to know (src/render/raster/draw.rs for the graphics pipeline, src/render/raster/compute/).
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

use super::adjacency::{linked_triangle, LINK_SAME_WAY};
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
    /// Whether this mesh bounds a solid (`Open` for one too large to link, which cannot be
    /// rendered either).
    pub fn solidity(&self) -> Solidity {
        self.solidity_with(&self.edge_links())
    }

    /// As [`Mesh::solidity`], given the mesh's [`Mesh::edge_links`] (the upload has them
    /// already).
    pub(crate) fn solidity_with(&self, links: &[[u32; 3]]) -> Solidity {
        debug_assert_eq!(links.len(), self.triangles.len());
        // Closed and consistently wound: every edge links two triangles that run it in opposite
        // directions (adjacency.rs links an edge only where exactly two share it; an edge from a
        // point to itself runs the same way in both).
        if !links.iter().flatten().all(|&link| link != NO_NEIGHBOUR && link & LINK_SAME_WAY == 0) {
            return Solidity::Open;
        }
        let mut sign = 0.0;
        for shell in shells(links) {
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
}

/// The triangles of each connected shell, across linked edges.
fn shells(links: &[[u32; 3]]) -> Vec<Vec<u32>> {
    let mut seen = vec![false; links.len()];
    let mut shells = Vec::new();
    for start in 0..links.len() {
        if seen[start] {
            continue;
        }
        seen[start] = true;
        let mut shell = vec![start as u32];
        let mut next = 0;
        while next < shell.len() {
            for n in links[shell[next] as usize].map(linked_triangle) {
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

    /// Both meshes' triangles in one mesh.
    fn join(a: &Mesh, b: &Mesh) -> Mesh {
        let offset = a.positions.len() as u32;
        let vertices = |m: &Mesh| (0..m.positions.len() as u32).map(|v| m.vertex(v).to_array()).collect::<Vec<_>>();
        let positions = [vertices(a), vertices(b)].concat();
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
        let positions = (0..8).map(|i| [(i & 1) as f64, ((i >> 1) & 1) as f64, ((i >> 2) & 1) as f64]).collect();
        let quads = [[0, 2, 3, 1], [4, 5, 7, 6], [0, 1, 5, 4], [2, 6, 7, 3], [0, 4, 6, 2], [1, 3, 7, 5]];
        let triangles: Vec<[u32; 3]> = quads.iter().flat_map(|&[a, b, c, d]| [[a, b, c], [a, c, d]]).collect();
        Mesh::new("cube", positions, triangles, vec![1; 12], vec!["s".into()]).unwrap()
    }

    #[test]
    fn a_cube_wound_outward_or_inward_bounds_a_solid() {
        assert_eq!(cube().solidity(), Solidity::Outward);
        assert_eq!(inside_out(cube()).solidity(), Solidity::Inward);
    }

    #[test]
    fn an_open_or_inconsistent_cube_is_open() {
        let mut open = cube();
        open.triangles.pop();
        open.triangle_surfaces.pop();
        assert_eq!(open.solidity(), Solidity::Open);
        let mut flipped = cube();
        flipped.triangles[0].swap(1, 2);
        assert_eq!(flipped.solidity(), Solidity::Open);
    }

    #[test]
    fn shells_count_only_when_all_wound_the_same_way() {
        let apart = moved(cube(), [3.0, 0.0, 0.0], 1.0);
        assert_eq!(join(&cube(), &apart).solidity(), Solidity::Outward);
        assert_eq!(join(&cube(), &inside_out(apart)).solidity(), Solidity::Open);
        // A hollow cube, its cavity wound inward: the camera never sees the cavity, but the
        // shells' volumes differ in sign, and the rule keeps it whole.
        let cavity = inside_out(moved(cube(), [0.25, 0.25, 0.25], 0.5));
        assert_eq!(join(&cube(), &cavity).solidity(), Solidity::Open);
    }

    #[test]
    fn a_double_sided_sheet_encloses_nothing() {
        let positions = vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
        let sheet = Mesh::new("sheet", positions, vec![[0, 1, 2], [0, 2, 1]], vec![1, 1], vec!["s".into()]).unwrap();
        assert_eq!(sheet.solidity(), Solidity::Open);
    }

    #[test]
    fn the_builtin_solids_are_wound_outward() {
        for name in ["builtin:box", "builtin:cylinder", "builtin:sphere", "builtin:sphere:320"] {
            let mesh = builtin_mesh(name).unwrap();
            assert_eq!(mesh.solidity(), Solidity::Outward, "{name}");
        }
        // The stepped block's sides end where its bottom has no corner (T-junctions), and its
        // +y side is wound like its −y side: it is drawn whole.
        assert_eq!(builtin_mesh("builtin:step").unwrap().solidity(), Solidity::Open);
        assert_eq!(builtin_mesh("builtin:plane").unwrap().solidity(), Solidity::Open);
    }
}
