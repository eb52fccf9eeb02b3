//! OBJ loading through tobj, from bytes read safely (io/input_file.rs).
//!
//! Surfaces (DESIGN.md "Interfaces"): every group (`g`) or object (`o`) statement is one
//! surface, numbered from 1 in the order the statements appear in the file, whether or not
//! it holds faces, so the numbering is the one a reader counts in the file (an empty group
//! keeps its number and simply has no pixels). Faces that come before any statement form a
//! surface of their own, numbered first. A file with at most one surface says nothing about
//! its surfaces, so they are found by merging edge-adjacent coplanar triangles.
//!
//! Before tobj sees the text, each line loses its comment (`#` to the end of the line, which
//! tobj would otherwise read as vertex colours), and each group statement is replaced by one
//! whose name is the statement's number, so tobj's models map back to statements exactly
//! (tobj drops empty groups and may split one at a `usemtl`). Materials, texture coordinates
//! and normals are dropped: nothing uses them, a `mtllib` can name any file, and tobj's
//! arithmetic on huge texture or normal indices overflows.

use super::{merge_coplanar_surfaces, Mesh};
use crate::error::{Error, Result};
use crate::io::read_input_file;
use crate::limits::MemoryBudget;
use std::path::Path;

/// Bytes of memory loading takes per byte of OBJ text, at most: tobj keeps every face as its
/// own small vector while parsing (about 100 bytes for an 8-byte `f 1 2 3` line).
const OBJ_EXPANSION: u64 = 16;

pub fn load_obj(path: &Path, budget: MemoryBudget) -> Result<Mesh> {
    let bytes = read_input_file(path, "model", budget, OBJ_EXPANSION)?;
    parse_obj(&bytes, &path.display().to_string())
}

/// Parses OBJ text; `name` is the mesh's name in messages.
pub fn parse_obj(bytes: &[u8], name: &str) -> Result<Mesh> {
    let text = String::from_utf8_lossy(bytes);
    let (tagged, statement_names) = tag_group_statements(&text);
    let options = tobj::LoadOptions { single_index: true, triangulate: true, ignore_points: true, ignore_lines: true };
    let no_materials = |_: &Path| Ok((Vec::new(), Default::default()));
    let (models, _) = tobj::load_obj_buf(&mut tagged.as_bytes(), &options, no_materials)
        .map_err(|e| Error::Mesh { name: name.to_string(), reason: format!("not a readable OBJ file ({e})") })?;

    // Statement 0 is the implicit group before any statement; it is a surface only when it
    // holds faces.
    let group_of = |model: &tobj::Model| model.name.parse::<usize>().expect("every group statement was tagged");
    let implicit = usize::from(models.iter().any(|m| group_of(m) == 0 && !m.mesh.indices.is_empty()));
    let surface_of = |group: usize| (group + implicit) as u32;
    let surface_names: Vec<String> = (1 - implicit..statement_names.len())
        .map(|group| match &statement_names[group] {
            Some(n) => n.clone(),
            None => format!("surface{}", surface_of(group)),
        })
        .collect();

    let mut positions = Vec::new();
    let mut triangles = Vec::new();
    let mut triangle_surfaces = Vec::new();
    for model in &models {
        let base = positions.len() as u32;
        positions.extend(model.mesh.positions.chunks_exact(3).map(|c| [c[0], c[1], c[2]]));
        for tri in model.mesh.indices.chunks_exact(3) {
            triangles.push([tri[0], tri[1], tri[2]].map(|i| i.saturating_add(base)));
            triangle_surfaces.push(surface_of(group_of(model)));
        }
    }
    let single_surface = surface_names.len() <= 1;
    let mesh = Mesh::new(name, positions, triangles, triangle_surfaces, surface_names)?;
    Ok(if single_surface { merge_coplanar_surfaces(mesh) } else { mesh })
}

/// The text with comments removed and group statement k (from 1, in file order) renamed to
/// `g k`, an implicit `g 0` first; and each statement's name (`None` when it has none),
/// index 0 being the implicit group's.
fn tag_group_statements(text: &str) -> (String, Vec<Option<String>>) {
    let mut names = vec![None];
    let mut tagged = String::with_capacity(text.len() + 4);
    tagged.push_str("g 0\n");
    for line in text.lines() {
        let line = line.split('#').next().unwrap_or("").trim();
        let mut words = line.splitn(2, char::is_whitespace);
        match words.next() {
            Some("g" | "o") => {
                let name = words.next().map(str::trim).filter(|n| !n.is_empty()).map(str::to_string);
                tagged.push_str(&format!("g {}\n", names.len()));
                names.push(name);
            }
            // Nothing uses materials, texture coordinates or normals: dropping them spares
            // tobj's index arithmetic on them (which overflows on huge indices).
            Some("mtllib" | "usemtl" | "vt" | "vn") => {}
            Some("f") => {
                tagged.push('f');
                for corner in words.next().unwrap_or("").split_whitespace() {
                    tagged.push(' ');
                    tagged.push_str(corner.split('/').next().unwrap_or(""));
                }
                tagged.push('\n');
            }
            _ => {
                tagged.push_str(line);
                tagged.push('\n');
            }
        }
    }
    (tagged, names)
}

#[cfg(test)]
mod tests {
    use super::*;

    const SQUARE: &str = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n";

    #[test]
    fn surfaces_follow_the_statements_in_file_order_empty_ones_included() {
        let text = format!("{SQUARE}g empty\no first\nf 1 2 3\ng\ng second\nf 1 3 4\n");
        let mesh = parse_obj(text.as_bytes(), "t").unwrap();
        assert_eq!(mesh.surface_names, ["empty", "first", "surface3", "second"]);
        assert_eq!(mesh.triangle_surfaces, [2, 4]);
    }

    #[test]
    fn faces_before_any_statement_are_the_first_surface() {
        let text = format!("{SQUARE}f 1 2 3\ng top\nf 1 3 4\n");
        let mesh = parse_obj(text.as_bytes(), "t").unwrap();
        assert_eq!(mesh.surface_names, ["surface1", "top"]);
        assert_eq!(mesh.triangle_surfaces, [1, 2]);
    }

    #[test]
    fn trailing_comments_and_materials_are_ignored() {
        let text = "mtllib /dev/zero\nv 0 1 0 # a comment\nv 1 1 0#another\nv 0 0 0\nusemtl x\nf 1 2 3 # face\n";
        let mesh = parse_obj(text.as_bytes(), "t").unwrap();
        assert_eq!(mesh.positions[0], [0.0, 1.0, 0.0]);
        assert_eq!(mesh.triangles.len(), 1);
    }
}
