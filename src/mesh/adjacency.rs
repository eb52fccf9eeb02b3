//! Which triangle lies across each edge of each triangle, so that the depth-mode shadow test
//! can walk over a surface from the triangle a shadow-buffer pixel saw to the one over a
//! point, however much smaller than a pixel the triangles are (shaders/stages/shadow_mask.comp).
//!
//! Vertices are matched by position, not index: OBJ files often repeat a vertex for each
//! normal or texture coordinate it carries, and the surface is still one surface. An edge
//! shared by exactly two triangles links them; a border edge, or one shared by three or more
//! triangles (where "across" means nothing), links nothing. The walk reads links that also
//! say which edge of the neighbour is the shared one and which way it runs
//! ([`Mesh::edge_links`]): it then reads only the neighbour's third corner.

use super::Mesh;
use std::collections::HashMap;

pub use crate::shader_contract::NO_NEIGHBOUR;

/// An edge link (see [`Mesh::edge_links`]) holds the neighbour's index shifted by this.
pub const LINK_INDEX_SHIFT: u32 = 3;
/// The link's bit set when the neighbour runs the shared edge the same way.
pub const LINK_SAME_WAY: u32 = 1 << 2;
/// The link's bits giving which edge of the neighbour is the shared one.
pub const LINK_EDGE_MASK: u32 = 0b11;
/// Triangles a mesh may have for its links to hold every index.
pub const MAX_LINKED_TRIANGLES: usize = 1 << (32 - LINK_INDEX_SHIFT);

/// For each vertex, the first vertex at the same position (position bits, with −0 read as +0).
pub(super) fn weld_vertices(positions: &[[f32; 3]]) -> Vec<u32> {
    let mut first: HashMap<[u32; 3], u32> = HashMap::new();
    positions
        .iter()
        .enumerate()
        .map(|(i, p)| *first.entry(p.map(|c| (c + 0.0).to_bits())).or_insert(i as u32))
        .collect()
}

/// The triangle an edge link names, or NO_NEIGHBOUR.
pub(super) fn linked_triangle(link: u32) -> u32 {
    match link {
        NO_NEIGHBOUR => NO_NEIGHBOUR,
        link => link >> LINK_INDEX_SHIFT,
    }
}

impl Mesh {
    /// For each triangle [a, b, c], the triangles across its edges a–b, b–c and c–a.
    pub fn triangle_neighbours(&self) -> Vec<[u32; 3]> {
        self.edge_links().iter().map(|links| links.map(linked_triangle)).collect()
    }

    /// For each triangle, what lies across each of its edges, as the depth test's walk reads
    /// it: NO_NEIGHBOUR, or the neighbour's index (shifted by [`LINK_INDEX_SHIFT`]), which of
    /// its edges is the shared one ([`LINK_EDGE_MASK`]) and whether it runs that edge the same
    /// way ([`LINK_SAME_WAY`]), so that the walk reads only the neighbour's third corner. A
    /// mesh of more than [`MAX_LINKED_TRIANGLES`] triangles links none.
    pub(crate) fn edge_links(&self) -> Vec<[u32; 3]> {
        let mut links = vec![[NO_NEIGHBOUR; 3]; self.triangles.len()];
        if self.triangles.len() > MAX_LINKED_TRIANGLES {
            return links;
        }
        let welded = weld_vertices(&self.positions);
        let corner = |t: u32, k: u8| welded[self.triangles[t as usize][usize::from(k) % 3] as usize];
        // (edge as sorted welded ids, triangle, edge slot), sorted so that copies of one edge meet.
        let mut edges: Vec<(u64, u32, u8)> = Vec::with_capacity(3 * self.triangles.len());
        for t in 0..self.triangles.len() as u32 {
            for k in 0..3 {
                let (a, b) = (corner(t, k), corner(t, k + 1));
                let edge = (u64::from(a.min(b)) << 32) | u64::from(a.max(b));
                edges.push((edge, t, k));
            }
        }
        edges.sort_unstable();
        for group in edges.chunk_by(|x, y| x.0 == y.0) {
            if let [(_, t, k), (_, u, l)] = *group {
                let same_way = if corner(t, k) == corner(u, l) { LINK_SAME_WAY } else { 0 };
                links[t as usize][usize::from(k)] = (u << LINK_INDEX_SHIFT) | same_way | u32::from(l);
                links[u as usize][usize::from(l)] = (t << LINK_INDEX_SHIFT) | same_way | u32::from(k);
            }
        }
        links
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_split_square_links_its_two_triangles_across_the_diagonal_only() {
        // Vertex 4 repeats vertex 2's position, as an OBJ with per-face normals would.
        let positions = vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 1.0, 0.0], [1.0, 1.0, -0.0]];
        let mesh = Mesh::new("square", positions, vec![[0, 1, 2], [0, 4, 3]], vec![1, 1], vec!["s".into()]).unwrap();
        assert_eq!(mesh.triangle_neighbours(), vec![[NO_NEIGHBOUR, NO_NEIGHBOUR, 1], [0, NO_NEIGHBOUR, NO_NEIGHBOUR]]);
    }

    #[test]
    fn an_edge_of_three_triangles_links_none_of_them() {
        let positions = vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.5, 1.0, 0.0], [0.5, -1.0, 0.0], [0.5, 0.0, 1.0]];
        let triangles = vec![[0, 1, 2], [1, 0, 3], [0, 1, 4]];
        let mesh = Mesh::new("fin", positions, triangles, vec![1; 3], vec!["s".into()]).unwrap();
        assert!(mesh.triangle_neighbours().iter().all(|n| *n == [NO_NEIGHBOUR; 3]));
    }

    #[test]
    fn a_link_names_the_neighbours_edge_and_its_direction() {
        let positions = vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 1.0, 0.0]];
        let square = |second: [u32; 3]| {
            Mesh::new("square", positions.clone(), vec![[0, 1, 2], second], vec![1, 1], vec!["s".into()]).unwrap()
        };
        // Triangle 0 runs the diagonal 2 → 0 as its edge c–a (slot 2). [0, 2, 3] runs it
        // 0 → 2 as its edge a–b (slot 0): the other way.
        let links = square([0, 2, 3]).edge_links();
        assert_eq!((links[0][2], links[1][0]), (1 << LINK_INDEX_SHIFT, 2));
        // [0, 3, 2] runs it 2 → 0 as its edge c–a (slot 2): the same way.
        let links = square([0, 3, 2]).edge_links();
        assert_eq!(links[0][2], (1 << LINK_INDEX_SHIFT) | LINK_SAME_WAY | 2);
        assert_eq!(links[1][2], LINK_SAME_WAY | 2);
    }
}
