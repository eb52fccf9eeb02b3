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
//! (tobj drops empty groups and may split one at a `usemtl`). Texture coordinates and normals
//! are dropped: nothing uses them, and tobj's arithmetic on huge texture or normal indices
//! overflows.
//!
//! Materials give each surface a reflectivity (`[effects.reflectivity]`): the mean of the
//! `Kd` of the material its first face uses. A file loaded from a path reads its `mtllib`
//! libraries from its directory, as every input is read (regular files within the budget);
//! a library that cannot be read is skipped, and its surfaces take the effect's default.
//! Text parsed without a path reads no library.

use super::{is_degenerate, merge_coplanar_surfaces, Mesh};
use crate::error::{Error, Result};
use crate::io::read_input_file;
use crate::limits::MemoryBudget;
use std::path::Path;

/// Bytes of memory loading takes per byte of OBJ text, at most: tobj keeps every face as its
/// own small vector while parsing (about 100 bytes for an 8-byte `f 1 2 3` line).
const OBJ_EXPANSION: u64 = 16;

pub fn load_obj(path: &Path, budget: MemoryBudget) -> Result<Mesh> {
    let bytes = read_input_file(path, "model", budget, OBJ_EXPANSION)?;
    let dir = path.parent().unwrap_or(Path::new("."));
    let libraries = |library: &Path| {
        let bytes = read_input_file(&dir.join(library), "material library", budget, OBJ_EXPANSION)
            .map_err(|_| tobj::LoadError::OpenFileFailed)?;
        tobj::load_mtl_buf(&mut bytes.as_slice())
    };
    parse(&bytes, &path.display().to_string(), libraries)
}

/// Parses OBJ text; `name` is the mesh's name in messages. Material libraries are not read.
pub fn parse_obj(bytes: &[u8], name: &str) -> Result<Mesh> {
    parse(bytes, name, |_: &Path| Ok((Vec::new(), Default::default())))
}

fn parse(bytes: &[u8], name: &str, libraries: impl Fn(&Path) -> tobj::MTLLoadResult) -> Result<Mesh> {
    let text = String::from_utf8_lossy(bytes);
    let (tagged, statement_names) = tag_group_statements(&text);
    let options = tobj::LoadOptions { single_index: true, triangulate: true, ignore_points: true, ignore_lines: true };
    let (models, materials) = tobj::load_obj_buf(&mut tagged.as_bytes(), &options, libraries)
        .map_err(|e| Error::Mesh { name: name.to_string(), reason: format!("not a readable OBJ file ({e})") })?;
    let materials = materials.unwrap_or_default();

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
    let mut triangle_reflectivity = Vec::new();
    for model in &models {
        let base = positions.len() as u32;
        positions.extend(model.mesh.positions.chunks_exact(3).map(|c| [c[0], c[1], c[2]]));
        let material = model.mesh.material_id.and_then(|id| materials.get(id)).and_then(reflectivity);
        for tri in model.mesh.indices.chunks_exact(3) {
            triangles.push([tri[0], tri[1], tri[2]].map(|i| i.saturating_add(base)));
            triangle_surfaces.push(surface_of(group_of(model)));
            triangle_reflectivity.push(material);
        }
    }
    // Aligned with the triangles Mesh::new keeps.
    let kept_reflectivity: Vec<Option<f32>> = triangles
        .iter()
        .zip(triangle_reflectivity)
        .filter(|(tri, _)| !is_degenerate(&positions, tri))
        .map(|(_, r)| r)
        .collect();
    let single_surface = surface_names.len() <= 1;
    let mesh = Mesh::new(name, positions, triangles, triangle_surfaces, surface_names)?;
    let mut mesh = if single_surface { merge_coplanar_surfaces(mesh) } else { mesh };
    // Each surface takes its first face's material.
    let mut seen = vec![false; mesh.surface_names.len()];
    for (&surface, &material) in mesh.triangle_surfaces.iter().zip(&kept_reflectivity) {
        let s = surface as usize - 1;
        if !std::mem::replace(&mut seen[s], true) {
            mesh.surface_reflectivity[s] = material;
        }
    }
    Ok(mesh)
}

/// A material's reflectivity: the mean of its diffuse colour `Kd`, within [0, 1].
fn reflectivity(material: &tobj::Material) -> Option<f32> {
    let kd = material.diffuse?;
    let mean = kd.iter().sum::<f32>() / 3.0;
    mean.is_finite().then(|| mean.clamp(0.0, 1.0))
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
            // Nothing uses texture coordinates or normals: dropping them spares tobj's index
            // arithmetic on them (which overflows on huge indices).
            Some("vt" | "vn") => {}
            // Material statements are passed on with one space, as tobj splits them; a
            // `usemtl` without a name is an error to tobj and names no material.
            Some(keyword @ ("usemtl" | "mtllib")) => {
                if let Some(name) = words.next().map(str::trim).filter(|n| !n.is_empty()) {
                    tagged.push_str(&format!("{keyword} {name}\n"));
                }
            }
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
    fn materials_give_each_surface_the_mean_of_its_kd() {
        let dir = crate::io::scratch_dir("obj_materials");
        std::fs::write(dir.join("m.mtl"), "newmtl dark\nKd 0.1 0.2 0.3\nnewmtl bright\nKd 0.9 0.9 0.6\n").unwrap();
        let text = format!(
            "mtllib m.mtl\nmtllib missing.mtl\n{SQUARE}g a\nusemtl bright\nf 1 2 3\ng b\nf 1 3 4\n\
             g c\nusemtl dark\nf 1 2 4\nusemtl bright\nf 2 3 4\ng d\nusemtl unknown\nf 1 2 3\n"
        );
        std::fs::write(dir.join("m.obj"), text).unwrap();
        let mesh = load_obj(&dir.join("m.obj"), MemoryBudget::default()).unwrap();
        assert_eq!(mesh.surface_names, ["a", "b", "c", "d"]);
        // b keeps using the material set before it; c takes its first face's.
        let expected = [Some(0.8), Some(0.8), Some(0.2), None];
        // Tabs after the keywords, and an ungrouped file with two materials: its merged faces
        // each take their own triangle's.
        let ungrouped = "mtllib\tm.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 0 1\nv 1 0 1\n\
                         usemtl\tdark\nf 1 2 3\nusemtl bright\nf 1 2 5 4\n";
        std::fs::write(dir.join("u.obj"), ungrouped).unwrap();
        let merged = load_obj(&dir.join("u.obj"), MemoryBudget::default()).unwrap();
        assert_eq!(merged.surface_names.len(), 2);
        let rounded: Vec<_> = merged.surface_reflectivity.iter().map(|r| r.map(|r| (r * 1e5).round() / 1e5)).collect();
        assert_eq!(rounded, [Some(0.2), Some(0.8)]);
        for (got, want) in mesh.surface_reflectivity.iter().zip(expected) {
            assert_eq!(got.map(|r| (r * 1e5).round() / 1e5), want);
        }
        let parsed = parse_obj(&std::fs::read(dir.join("m.obj")).unwrap(), "text").unwrap();
        assert!(parsed.surface_reflectivity.iter().all(Option::is_none), "text alone reads no library");
    }

    #[test]
    fn trailing_comments_and_materials_are_ignored() {
        let text = "mtllib /dev/zero\nv 0 1 0 # a comment\nv 1 1 0#another\nv 0 0 0\nusemtl x\nf 1 2 3 # face\n";
        let mesh = parse_obj(text.as_bytes(), "t").unwrap();
        assert_eq!(mesh.positions[0], [0.0, 1.0, 0.0]);
        assert_eq!(mesh.triangles.len(), 1);
    }
}
