//! Which triangle lies across each edge of each triangle, so that the depth-mode shadow test
//! can walk over a surface from the triangle a shadow-buffer pixel saw to the one over a
//! point, however much smaller than a pixel the triangles are (shaders/shadow_mask.comp).
//!
//! Vertices are matched by position, not index: OBJ files often repeat a vertex for each
//! normal or texture coordinate it carries, and the surface is still one surface. An edge
//! shared by exactly two triangles links them; a border edge, or one shared by three or more
//! triangles (where "across" means nothing), links nothing.

use super::Mesh;
use std::collections::HashMap;

/// Neighbour value of an edge that links no triangle; `NO_NEIGHBOUR` in shaders/draw.glsl.
pub const NO_NEIGHBOUR: u32 = u32::MAX;

/// For each vertex, the first vertex at the same position (position bits, with −0 read as +0).
pub(super) fn weld_vertices(positions: &[[f32; 3]]) -> Vec<u32> {
    let mut first: HashMap<[u32; 3], u32> = HashMap::new();
    positions
        .iter()
        .enumerate()
        .map(|(i, p)| *first.entry(p.map(|c| (c + 0.0).to_bits())).or_insert(i as u32))
        .collect()
}

impl Mesh {
    /// For each triangle [a, b, c], the triangles across its edges a–b, b–c and c–a.
    pub fn triangle_neighbours(&self) -> Vec<[u32; 3]> {
        let welded = weld_vertices(&self.positions);
        // (edge as sorted welded ids, triangle, edge slot), sorted so that copies of one edge meet.
        let mut edges: Vec<(u64, u32, u8)> = Vec::with_capacity(3 * self.triangles.len());
        for (t, tri) in self.triangles.iter().enumerate() {
            for k in 0..3 {
                let (a, b) = (welded[tri[k] as usize], welded[tri[(k + 1) % 3] as usize]);
                let edge = (u64::from(a.min(b)) << 32) | u64::from(a.max(b));
                edges.push((edge, t as u32, k as u8));
            }
        }
        edges.sort_unstable();
        let mut neighbours = vec![[NO_NEIGHBOUR; 3]; self.triangles.len()];
        for group in edges.chunk_by(|x, y| x.0 == y.0) {
            if let [(_, t, k), (_, u, l)] = *group {
                neighbours[t as usize][k as usize] = u;
                neighbours[u as usize][l as usize] = t;
            }
        }
        neighbours
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
}
