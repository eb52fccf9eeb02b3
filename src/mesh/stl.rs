//! STL models (ASCII and binary: what every CAD exporter writes) through stl_io, from bytes
//! read safely (io/input_file.rs).
//!
//! stl_io reads a triangle at a time and reserves nothing from the binary header's triangle
//! count, so what a file can turn into is bounded by its size alone (a binary triangle takes
//! 50 bytes, an ASCII facet more), and is charged to the run's budget before it is read.
//! Triangles are kept unindexed (three vertices each): their corners are matched by
//! position wherever the mesh needs neighbours (src/mesh/adjacency.rs). STL has no groups, so
//! its surfaces are derived from its geometry (smooth by default) as an OBJ's without groups are.

use super::surfaces::default_surfaces;
use super::Mesh;
use crate::error::{guard_parser, Error, Result};
use crate::io::read_input_file;
use crate::limits::Ledger;
use crate::untrusted::parser_error;
use std::io::Cursor;
use std::path::Path;

/// Bytes parsing takes, at most, per byte of the file: a binary triangle's 50 bytes become
/// three f64 corners with room for their vector's doubling, then the mesh and its surfaces'
/// grouping, whose open edges a triangle soup has three of (measured with a counting
/// allocator: tests/memory.rs).
const BYTES_PER_FILE_BYTE: u64 = 10;

pub fn load_stl(path: &Path, ledger: &Ledger) -> Result<Mesh> {
    let bytes = read_input_file(path, "model", ledger)?;
    parse_stl(&bytes, &path.display().to_string(), ledger)
}

/// Parses an STL model held in memory; `name` names it in messages and in the mesh.
pub fn parse_stl(bytes: &[u8], name: &str, ledger: &Ledger) -> Result<Mesh> {
    let invalid = |reason: String| Error::Mesh { name: name.to_string(), reason };
    ledger.charge(format_args!("parsing {name}"), bytes.len() as u64 * BYTES_PER_FILE_BYTE)?;
    let positions = guard_parser(name, "stl_io's STL parser", || {
        let mut cursor = Cursor::new(bytes);
        let triangles = stl_io::create_stl_reader(&mut cursor)
            .map_err(|e| invalid(format!("not a readable STL file ({})", parser_error(e))))?;
        let mut positions: Vec<[f64; 3]> = Vec::new();
        for (t, triangle) in triangles.enumerate() {
            let triangle = triangle.map_err(|e| invalid(format!("triangle {t} unreadable ({})", parser_error(e))))?;
            positions.extend(triangle.vertices.map(|v| v.0.map(f64::from)));
        }
        Ok(positions)
    })?;
    let count = positions.len() as u32 / 3;
    let triangles = (0..count).map(|t| [3 * t, 3 * t + 1, 3 * t + 2]).collect();
    let mesh = Mesh::new(name, positions, triangles, vec![1; count as usize], vec!["surface1".to_string()])?;
    Ok(default_surfaces(mesh))
}
